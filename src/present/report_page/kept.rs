//! The kept evaluation reports the page shows: each `eval_*.json` that `eval` keeps under a data
//! directory's `reports/` (DATA's own, and each `improve` round's), read and checked, with the
//! settings that decide what it can be compared with (present::kept_reports) and the files it
//! recorded, found again where they lie now.

use std::path::{Path, PathBuf};

use crate::named::Named;
use crate::policy::PolicyKind;
use crate::present::eval_report::{EvalReport, Task};
use crate::present::kept_reports::Comparable;

/// One kept report, read and checked.
pub(super) struct Entry {
    pub(super) path: PathBuf,
    pub(super) file_name: String,
    pub(super) task: Task,
    pub(super) policy: PolicyKind,
    pub(super) settings: Comparable,
    pub(super) report: EvalReport,
    /// The data directory whose `reports/` kept it: the files it recorded are looked for there.
    pub(super) home: PathBuf,
    /// The folder of the report's files that holds its pictures and video: one per kept report
    /// (`eval_train_model.json` → `train_model/`, an improve round's under its own prefix), so
    /// that runs of one task and policy with other settings keep their own pictures.
    pub(super) folder: String,
    /// Its copy's path in the report's files: `reports/<name>`, an improve round's with the
    /// round's prefix, as rounds keep reports under the same names as DATA does.
    pub(super) copy_name: String,
}

impl Entry {
    /// Where a file the evaluation recorded lies now (see [`locate`]).
    pub(super) fn locate(&self, recorded: &Path) -> Option<PathBuf> {
        locate(recorded, &self.report.config.global.data, &self.home)
    }

    /// Every attempt picture the evaluation drew, in order.
    pub(super) fn pictures(&self) -> Vec<Picture> {
        let runs = &self.report.results.runs;
        runs.iter()
            .flat_map(|run| run.attempts.iter().map(move |a| (run, a)))
            .filter_map(|(run, a)| {
                let path = a.vis.clone()?;
                Some(Picture {
                    path,
                    seed: run.seed,
                    attempt: a.attempt,
                    what: a.object.clone().unwrap_or_else(|| "scene".into()),
                    outcome: if a.success {
                        "success".into()
                    } else {
                        a.reason.name().into()
                    },
                })
            })
            .collect()
    }

    /// The episode video the evaluation recorded, as recorded (it may be gone).
    pub(super) fn recorded_video(&self) -> Option<&PathBuf> {
        let r = &self.report;
        r.results.video.as_ref().or(r.config.record.as_ref())
    }
}

/// One attempt's picture, as the report recorded it.
pub(super) struct Picture {
    /// Where `eval` wrote it.
    pub(super) path: PathBuf,
    /// The scene's base seed.
    pub(super) seed: u64,
    /// The attempt's number.
    pub(super) attempt: u32,
    /// The object alone in the bin, or "scene".
    pub(super) what: String,
    /// "success" or the failure's reason.
    pub(super) outcome: String,
}

/// A task's kept reports, one group per set of comparable settings (the defaults first, then in
/// the settings' order), each group's reports in policy order (model, random, oracle).
pub(super) fn groups<'a>(entries: impl Iterator<Item = &'a Entry>) -> Vec<Vec<&'a Entry>> {
    let mut mine: Vec<&Entry> = entries.collect();
    mine.sort_by(|a, b| {
        (!a.settings.is_default(), &a.settings, a.file_name.as_str()).cmp(&(
            !b.settings.is_default(),
            &b.settings,
            b.file_name.as_str(),
        ))
    });
    let mut groups: Vec<Vec<&Entry>> = Vec::new();
    for entry in mine {
        match groups.last_mut() {
            Some(group) if group[0].settings == entry.settings => group.push(entry),
            _ => groups.push(vec![entry]),
        }
    }
    for group in &mut groups {
        group.sort_by_key(|e| PolicyKind::ALL.iter().position(|&p| p == e.policy));
    }
    groups
}

/// Reads every `eval_*.json` under `home/reports`, in name order; `prefix` starts the name of
/// each one's folder of pictures.
pub(super) fn read_kept(home: &Path, prefix: &str) -> anyhow::Result<Vec<Entry>> {
    let Ok(listing) = std::fs::read_dir(home.join("reports")) else {
        return Ok(Vec::new());
    };
    let mut paths: Vec<PathBuf> = listing
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with("eval_") && n.ends_with(".json"))
        })
        .collect();
    paths.sort();
    paths
        .into_iter()
        .map(|path| read_one(&path, home, prefix))
        .collect()
}

fn read_one(path: &Path, home: &Path, prefix: &str) -> anyhow::Result<Entry> {
    // The one strict reader of eval reports: what merge and --resume accept, the page shows.
    let report = EvalReport::read(path, "delete it, or run that evaluation again")?;
    let (task, policy) = (report.config.task, report.config.policy);
    let config = &report.config;
    let settings = Comparable::new(
        task,
        &config.seeds,
        config.max_attempts,
        config.give_up_after,
        &config.global.objects_dir,
        &config.global.split_path,
        &config.objects,
        config.shard.clone(),
    );
    let file_name = path
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    let folder = file_name
        .strip_prefix("eval_")
        .and_then(|n| n.strip_suffix(".json"))
        .map_or_else(
            || format!("{}_{}", task.name(), policy.name()),
            str::to_owned,
        );
    let copy_name = format!("reports/{prefix}{file_name}");
    Ok(Entry {
        path: path.to_path_buf(),
        file_name,
        task,
        policy,
        settings,
        report,
        home: home.to_path_buf(),
        folder: format!("{prefix}{folder}"),
        copy_name,
    })
}

/// Where a path that a report recorded lies now: as recorded, or rebased from the data directory
/// the evaluation ran with onto the one this report reads.
fn locate(recorded: &Path, run_data: &Path, data_dir: &Path) -> Option<PathBuf> {
    if recorded.is_file() {
        return Some(recorded.to_path_buf());
    }
    let rebased = data_dir.join(recorded.strip_prefix(run_data).ok()?);
    rebased.is_file().then_some(rebased)
}
