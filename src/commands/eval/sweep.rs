//! A sweep beyond one run: the plan it announces, the report it keeps under DATA/reports (when
//! it finishes or is interrupted), and `--resume`, which reads that report back.

use std::path::{Path, PathBuf};

use anyhow::bail;

use super::config::{EvalConfig, ATTEMPTS_PER_OBJECT};
use crate::commands::{Context, RunBy};
use crate::interrupt;
use crate::named::{counted, Named};
use crate::policy::PolicyKind;
use crate::present::envelope::write_versioned_report;
use crate::present::eval_report::{summarise, EvalReport, SceneRun, Task};
use crate::present::kept_reports::Comparable;
use crate::sim::WorkcellConfig;

/// The settings that decide which runs this one can be compared with, and where its report is
/// kept (present::kept_reports).
pub(crate) fn comparable(context: &Context, config: &EvalConfig, names: &[String]) -> Comparable {
    Comparable::new(
        config.task,
        &config.seeds,
        config.max_attempts,
        config.give_up_after,
        &context.objects.location(),
        &context.split.location(),
        names,
        (!config.shard.is_whole()).then(|| config.shard.to_string()),
    )
}

/// Where this run keeps its report: `DATA/reports/eval_<task>_<policy>.json` for the default
/// settings, with a short key of the seeds, attempts and objects before `.json` for any others,
/// so that a smaller or different run never replaces another's report; and for a shard,
/// `_shard<I>of<N>`, so shards sharing a data folder keep one each.
pub(super) fn kept_path(context: &Context, config: &EvalConfig, names: &[String]) -> PathBuf {
    comparable(context, config, names).kept_path(&context.data, config.policy)
}

/// Writes the report of an interrupted sweep (the scenes finished so far) and says how to
/// continue; returns the error that ends the command with the signal's status.
pub(super) fn keep_interrupted(
    context: &Context,
    config: &EvalConfig,
    names: &[String],
    runs: Vec<SceneRun>,
    elapsed: f64,
    interrupted: interrupt::Interrupted,
) -> anyhow::Error {
    let seeds = &config.run_seeds();
    let written = (|| -> anyhow::Result<()> {
        let kept = format!("{} of {} scenes", runs.len(), seeds.len());
        let results = summarise(
            config.task,
            config.policy,
            seeds.clone(),
            names,
            runs,
            elapsed,
            true,
        );
        // The finished scenes always stay under DATA/reports, where `--resume` finds them, and
        // in the user's own --json copy when there is one.
        let resolved = resolved_config(context, config, names);
        let kept_path = kept_path(context, config, names);
        let own = context.json.as_ref().filter(|j| *j != Path::new("-"));
        for target in own.into_iter().chain(std::iter::once(&kept_path)) {
            write_versioned_report(target, "eval", 2, config.seeds[0], &resolved, &results)?;
        }
        let place = own.unwrap_or(&kept_path);
        context.stopped(&format!(
            "{interrupted}: {kept} kept in {}; {}",
            place.display(),
            match config.run_by {
                RunBy::Own => "rerun the same command with --resume to finish the rest",
                RunBy::Improve => "rerun the same improve command (its evaluation starts again)",
            }
        ));
        Ok(())
    })();
    match written {
        Ok(()) => interrupted.into(),
        Err(e) => e,
    }
}

/// The report `--resume` continues: the user's `--json` file when there is one, else the copy
/// kept under DATA/reports.
pub(super) fn resume_source<'a>(context: &'a Context, kept: &'a Path) -> &'a Path {
    match context.json.as_deref() {
        Some(json) if json != Path::new("-") => json,
        _ => kept,
    }
}

/// Typical wall seconds of one attempt on a 2-core machine, for the estimate printed before a
/// long sweep (BENCHMARKS.md#attempt-latency): empty_bin attempts render, check and settle a
/// full bin.
fn typical_attempt_seconds(task: Task) -> f64 {
    match task {
        Task::EmptyBin | Task::Scenes => 0.8,
        Task::Train | Task::Test => 0.4,
    }
}

/// Says how many attempts a sweep plans and, when it will take more than about a minute, how
/// long it should take.
pub(super) fn announce_plan(context: &Context, task: Task, per_scene: u64, scenes: usize) {
    let attempts = per_scene * scenes as u64;
    let seconds = attempts as f64 * typical_attempt_seconds(task);
    if context.quiet || seconds < 60.0 {
        return;
    }
    let hours = seconds / 3600.0;
    let estimate = if hours >= 1.0 {
        format!("{hours:.1} h")
    } else {
        format!("{:.0} min", seconds / 60.0)
    };
    let resume = match task {
        Task::Scenes => "",
        _ => ", --resume continues",
    };
    eprintln!(
        "eval: {} of up to {}, {attempts} attempts in all: about {estimate} at {} s an attempt; \
         Ctrl-C keeps the finished scenes{resume}",
        counted(scenes, "scene"),
        counted(per_scene as usize, "attempt"),
        typical_attempt_seconds(task)
    );
}

/// The scenes that an earlier report of the same evaluation holds, for `--resume`: those of
/// this run's seeds, checked to come from the same task, policy and settings.
pub(super) fn finished_runs(report: &Path, config: &EvalConfig) -> anyhow::Result<Vec<SceneRun>> {
    if !report.is_file() {
        return Ok(Vec::new());
    }
    let earlier = EvalReport::read(report, "delete it, or drop --resume")?;
    for (key, then, now) in [
        ("task", earlier.config.task.name(), config.task.name()),
        ("policy", earlier.config.policy.name(), config.policy.name()),
    ] {
        if then != now {
            bail!(
                "{} ran --{key} {then}, this run --{key} {now}; resume with the same settings",
                report.display()
            );
        }
    }
    let mine = config.run_seeds();
    Ok((earlier.results.runs.into_iter())
        .filter(|r| mine.contains(&r.seed))
        .collect())
}

/// The configuration as the report records it. `seeds` are the whole sweep's; a shard's report
/// adds `shard` ("I/N"), and its `results.seeds` are the shard's. A model's checkpoint is named
/// by path and by SHA-256, which `merge` compares.
pub(super) fn resolved_config(
    context: &Context,
    config: &EvalConfig,
    names: &[String],
) -> serde_json::Value {
    let model = config.policy == PolicyKind::Model;
    let mut resolved = serde_json::json!({
        "global": context,
        "task": config.task,
        "policy": config.policy,
        "checkpoint": model.then_some(&config.checkpoint),
        "precision": model.then_some(config.precision),
        "seeds": config.seeds,
        "suppression": config.suppression,
        "collision_check": model.then_some(config.model.check),
        "verify_top": model.then_some(config.model.verify_top),
        "verify_floor": model.then_some(config.model.verify_floor),
        "verify_rejected": model.then_some(config.model.verify_rejected),
        "verify_strips": model.then_some(config.model.verify_strips),
        "verify_square": model.then_some(config.model.verify_square),
        "verify_margin": model.then_some(config.model.verify_margin),
        "centring": model && config.model.centring,
        "max_attempts": config.max_attempts,
        "give_up_after": config.give_up_after,
        "push_unverified": model && config.push_unverified,
        "attempts_per_object": ATTEMPTS_PER_OBJECT,
        "objects": names,
        "workcell": WorkcellConfig::default(),
        "record": config.record,
    });
    if model {
        resolved["checkpoint_sha256"] = crate::model::checkpoint::file_sha256(&config.checkpoint)
            .map_or(serde_json::Value::Null, serde_json::Value::from);
    }
    if config.task == Task::Scenes {
        resolved["scenes"] = serde_json::json!(config.scenes);
    }
    if !config.shard.is_whole() {
        resolved["shard"] = serde_json::Value::from(config.shard.to_string());
    }
    resolved
}
