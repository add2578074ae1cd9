//! `graspmap improve`: the self-supervised loop. Each round collects trials with the current
//! model, then retrains from it on the labels and every round's trials so far (docs/learning.md,
//! "Learning from trials").
//!
//! Every stage is the real command with its own guarantees: a round's store resumes like
//! `collect`, its model like `train`, so an interrupted loop rerun with the same flags continues
//! where it stopped and ends with the same bytes.

use std::path::{Path, PathBuf};
use std::time::Instant;

use super::collect::CollectConfig;
use super::eval::{pushes_by_default, EvalConfig};
use super::train::TrainOptions;
use super::{Context, RunBy};
use crate::assets::objects::SplitFile;
use crate::data::input::InputKind;
use crate::data::seeds::{derived_seed, SeedOverflow};
use crate::data::shard::Shard;
use crate::data::trials::TrialStore;
use crate::model::config::TrainConfig;
use crate::model::unet::Precision;
use crate::named::shell_word;
use crate::policy::model::ModelPolicyConfig;
use crate::policy::suppression::SuppressionConfig;
use crate::policy::PolicyKind;
use crate::present::eval_report::{EvalReport, Task};
use crate::present::improve_summary::{self, EvalSummary, RoundSummary};
use crate::present::kept_reports::DEFAULT_MAX_ATTEMPTS;

/// The learning rate of a round's retraining. It starts from a model that already fits the
/// labels, and at train's 1e-3 a round could unlearn them where no trial looks: on one machine
/// round 2 scored the tote's rim above the objects, 30 of 90 test picks as the plain argmax
/// against 61 at this rate.
pub(crate) const ROUND_LR: f64 = 1e-4;

/// What `graspmap improve` runs, resolved by the CLI.
#[derive(Debug, Clone)]
pub(crate) struct ImproveConfig {
    /// Where the rounds go: `round_RR/trials` and `round_RR/model` each, and `summary.json`.
    pub(crate) out: PathBuf,
    /// Rounds of collect-then-retrain.
    pub(crate) rounds: u32,
    /// The model the first round collects with (the labelled model).
    pub(crate) start: PathBuf,
    /// The labels every round trains on as well.
    pub(crate) labels: PathBuf,
    /// The collection of every round; its store, seed and checkpoint are set per round.
    pub(crate) collect: CollectConfig,
    /// The retraining of every round; its seed is set per round.
    pub(crate) train: TrainConfig,
    /// Evaluate each round's model on empty_bin with these seeds.
    pub(crate) eval_seeds: Option<Vec<u64>>,
}

/// Runs the command.
pub(crate) fn run(context: &Context, config: ImproveConfig) -> anyhow::Result<()> {
    // The last round's seeds are the largest: when they fit, every round's do.
    stage_seed(config.collect.seed.max(config.train.seed), config.rounds)?;
    let start_meta = crate::model::checkpoint::read(
        &config.start,
        "train the labelled model first (graspmap train), or pass --checkpoint PATH",
    )?
    .meta;
    let input = start_meta.map_or_else(Default::default, |m| m.config.input);
    // So that `graspmap report` finds these rounds wherever --out put them.
    improve_summary::record_run(&context.data, &config.out)?;
    let mut summaries: Vec<RoundSummary> = Vec::new();
    let mut current = config.start.clone();
    let mut stores: Vec<PathBuf> = Vec::new();
    let start = Instant::now();
    for round in 1..=config.rounds {
        announce_left(context, round - 1, config.rounds, start.elapsed());
        let summary = run_round(context, &config, input, round, &current, &mut stores)?;
        summaries.push(RoundSummary {
            trials_so_far: summaries.iter().map(|s| s.trials).sum::<usize>() + summary.trials,
            ..summary
        });
        let summary = summaries.last().expect("just pushed");
        let dir = config.out.join(format!("round_{round:02}"));
        improve_summary::write(&dir.join(improve_summary::FILE), summary)?;
        improve_summary::write(&config.out.join(improve_summary::FILE), &summaries)?;
        context.say(&round_line(summary));
        current = summary.model.clone();
    }
    context.say(&format!(
        "the improved model is {}; evaluate it with {}",
        current.display(),
        eval_hint(context, &current)
    ));
    if let Some(json) = &context.json {
        let resolved = serde_json::json!({
            "global": context,
            "rounds": config.rounds,
            "out": config.out,
            "start": config.start,
            "scenes": config.collect.scenes,
            "eval_seeds": config.eval_seeds,
        });
        crate::present::envelope::write_report(
            json,
            "improve",
            config.collect.seed,
            &resolved,
            &summaries,
        )?;
    }
    Ok(())
}

/// On a terminal (the stages draw their own progress bars), between rounds: how long the
/// rounds left should take at the pace of those `done`, `elapsed` in all.
fn announce_left(context: &Context, done: u32, rounds: u32, elapsed: std::time::Duration) {
    if done == 0 || done >= rounds || !context.shows_progress() {
        return;
    }
    let left = elapsed / done * (rounds - done);
    eprintln!(
        "improve: {done} of {rounds} rounds done in {:#}; about {:#} left at that pace",
        indicatif::HumanDuration(elapsed),
        indicatif::HumanDuration(left)
    );
}

/// One round: collects with `current` into the round's store (added to `stores`), retrains
/// from it on the labels and every store so far, and evaluates the new model when asked. Its
/// summary's `trials_so_far` is left for the caller.
fn run_round(
    context: &Context,
    config: &ImproveConfig,
    input: InputKind,
    round: u32,
    current: &Path,
    stores: &mut Vec<PathBuf>,
) -> anyhow::Result<RoundSummary> {
    let dir = config.out.join(format!("round_{round:02}"));
    context.say(&format!(
        "round {round}/{}: collecting {} scenes with {}",
        config.rounds,
        config.collect.scenes,
        current.display()
    ));
    let collect_start = Instant::now();
    let collect = CollectConfig {
        out: dir.join("trials"),
        seed: stage_seed(config.collect.seed, round)?,
        checkpoint: current.to_path_buf(),
        run_by: RunBy::Improve,
        ..config.collect.clone()
    };
    super::collect::run(context, collect.clone())?;
    let collect_seconds = collect_start.elapsed().as_secs_f64();
    stores.push(collect.out.clone());

    context.say(&format!(
        "round {round}/{}: retraining from {} on the labels and {} trial store(s)",
        config.rounds,
        current.display(),
        stores.len()
    ));
    let train_start = Instant::now();
    let model = retrain(context, config, input, round, current, stores)?;
    let train_seconds = train_start.elapsed().as_secs_f64();

    let eval = match &config.eval_seeds {
        Some(seeds) => Some(evaluate(
            context,
            &dir,
            &model,
            seeds,
            config.collect.precision,
        )?),
        None => None,
    };
    let store = TrialStore::new(&collect.out);
    let tally = store.tally(&store.scenes()?)?;
    let best_val_loss = crate::model::checkpoint::read(&model, "rerun the same improve command")?
        .meta
        .map_or(f64::NAN, |m| m.best_val_loss);
    Ok(RoundSummary {
        round,
        collected_with: current.to_path_buf(),
        trials: tally.trials,
        successes: tally.successes,
        collection_success_rate: tally.successes as f64 / tally.trials.max(1) as f64,
        trials_so_far: 0,
        best_val_loss,
        model,
        collect_seconds,
        train_seconds,
        eval,
    })
}

/// Round `round`'s training: from `current`, on the labels and every store so far, into the
/// round's `model/` folder. Returns the new model.
fn retrain(
    context: &Context,
    config: &ImproveConfig,
    input: InputKind,
    round: u32,
    current: &Path,
    stores: &[PathBuf],
) -> anyhow::Result<PathBuf> {
    let model_dir = config.out.join(format!("round_{round:02}")).join("model");
    let train = TrainOptions {
        config: TrainConfig {
            seed: stage_seed(config.train.seed, round)?,
            input,
            ..config.train.clone()
        },
        resume: false,
        force: false,
        out_dir: model_dir.clone(),
        labels: Some(config.labels.clone()),
        trials: stores.to_vec(),
        start_from: Some(current.to_path_buf()),
        precision_auto: false,
        run_by: RunBy::Improve,
    };
    super::train::run(context, train)?;
    Ok(model_dir.join("best.safetensors"))
}

/// The seed of round `round`'s collection or training, from the one `seed` the user gave it:
/// its own, so rounds never repeat a scene or a data order. (Not label's `rounds::round_seed`,
/// the drop seed of a labelling round.)
fn stage_seed(seed: u64, round: u32) -> Result<u64, SeedOverflow> {
    derived_seed(seed, 1_000, u64::from(round), "seed·1000 + r for round r")
}

/// empty_bin with the round's model and failure memory 8, reported into the round's folder.
fn evaluate(
    context: &Context,
    dir: &Path,
    model: &Path,
    seeds: &[u64],
    precision: Precision,
) -> anyhow::Result<EvalSummary> {
    let start = Instant::now();
    let report = dir.join("eval_empty_bin.json");
    let eval_context = Context {
        data: dir.to_path_buf(),
        json: Some(report.clone()),
        ..context.clone()
    };
    let config = EvalConfig {
        task: Task::EmptyBin,
        policy: PolicyKind::Model,
        checkpoint: model.to_path_buf(),
        precision,
        seeds: seeds.to_vec(),
        scenes: Vec::new(),
        suppression: SuppressionConfig {
            remember: 8,
            ..SuppressionConfig::default()
        },
        model: ModelPolicyConfig::default(),
        max_attempts: DEFAULT_MAX_ATTEMPTS,
        give_up_after: 0,
        push_unverified: pushes_by_default(Task::EmptyBin),
        record: None,
        resume: false,
        check_invariants: false,
        shard: Shard::WHOLE,
        run_by: RunBy::Improve,
    };
    super::eval::run(&eval_context, config)?;
    let results = EvalReport::read(&report, "rerun the same improve command")?.results;
    let moved: Vec<f64> = (results.runs.iter())
        .filter_map(|r| r.bin.as_ref())
        .map(|b| b.moved as f64)
        .collect();
    // Over every attempt, pushes included (pick success in the report leaves pushes out).
    let attempts: Vec<bool> = (results.runs.iter())
        .flat_map(|r| &r.attempts)
        .map(|a| a.success)
        .collect();
    Ok(EvalSummary {
        seeds: seeds.to_vec(),
        moved_mean: moved.iter().sum::<f64>() / moved.len().max(1) as f64,
        pick_success_rate: attempts.iter().filter(|&&s| s).count() as f64
            / attempts.len().max(1) as f64,
        report,
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// The command that evaluates `model` on the test objects, as printed to run: the data
/// directory, objects and split of this run.
fn eval_hint(context: &Context, model: &Path) -> String {
    let word = |path: &Path| shell_word(&path.display().to_string());
    let mut hint = format!(
        "graspmap --data {} eval --task test --checkpoint {}",
        word(&context.data),
        word(model)
    );
    if let Some(dir) = context.objects.dir() {
        hint += &format!(" --objects-dir {}", word(dir));
    }
    if let SplitFile::Path(split) = &context.split {
        hint += &format!(" --split {}", word(split));
    }
    hint
}

fn round_line(summary: &RoundSummary) -> String {
    let mut line = format!(
        "round {}: {} trials ({:.1} % succeeded), best validation loss {:.5}, collect {:.0} s, train {:.0} s",
        summary.round,
        summary.trials,
        100.0 * summary.collection_success_rate,
        summary.best_val_loss,
        summary.collect_seconds,
        summary.train_seconds
    );
    if let Some(eval) = &summary.eval {
        line += &format!(
            "; empty_bin {:.1} moved, {:.1} % picks",
            eval.moved_mean,
            100.0 * eval.pick_success_rate
        );
    }
    line
}
