//! What an evaluation reports: the attempt records, per-object and per-scene tables, Wilson
//! intervals and timings, as JSON (`graspmap.eval/2`) and as printed lines.

use std::collections::BTreeMap;
use std::path::PathBuf;

use crate::grasp::PixelGrasp;
use crate::metrics::{median, FailureTally, Rate, Spread};
use crate::model::maps::Choice;
use crate::named::{counted, named_enum, Named};
use crate::policy::PolicyKind;
use crate::sim::pick::PickReason;
use crate::sim::ObjectLocation;

/// The default empty_bin scene (the reference's).
pub(crate) const DEFAULT_EMPTY_BIN_SEED: u64 = 2;

named_enum! {
    /// The evaluations, spelled as the reference spells them.
    #[derive(serde::Deserialize)]
    pub enum Task {
        /// Each training object alone, 3 attempts each.
        Train = "train", "each training object alone, 3 attempts each",
        /// Each test (unseen) object alone, 3 attempts each.
        Test = "test", "each test (unseen) object alone, 3 attempts each",
        /// All 15 objects in bin 1 at once; move as many as possible to bin 2.
        EmptyBin = "empty_bin", "all 15 objects in bin 1 at once; move as many as possible to bin 2",
    }
}

impl Task {
    /// The seed a run without `--seed` uses: 2 for empty_bin, 0 otherwise (the reference's).
    pub(crate) fn default_seed(self) -> u64 {
        match self {
            Task::EmptyBin => DEFAULT_EMPTY_BIN_SEED,
            Task::Train | Task::Test => 0,
        }
    }
}

/// Wall seconds of one attempt, by what they were spent on.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub(crate) struct AttemptTiming {
    /// Everything, from the drop (train/test) or the previous attempt (empty_bin) to the report.
    pub(crate) wall: f64,
    /// Physics: the drop (train/test) and the pick.
    pub(crate) sim: f64,
    /// The top-down camera image.
    pub(crate) render: f64,
    /// Rotations, network, suppression and argmax (model policy).
    pub(crate) network: f64,
}

/// One pick attempt.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub(crate) struct AttemptRecord {
    /// The scene's drop seed.
    pub(crate) drop_seed: u64,
    /// 0-based attempt number (per object in train/test, per scene in empty_bin).
    pub(crate) attempt: u32,
    /// train/test: the object alone in the bin.
    pub(crate) object: Option<String>,
    /// The grasp executed; absent when the policy found none.
    pub(crate) grasp: Option<PixelGrasp>,
    /// Model policy: the map the grasp came from and its score there.
    pub(crate) choice: Option<Choice>,
    /// Model policy with verification: whether the executed grasp passed it; false when
    /// nothing did and the argmax was executed anyway. Absent otherwise, and in older reports.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) verified: Option<bool>,
    /// Whether an object was lifted, carried and placed.
    pub(crate) success: bool,
    /// Why the attempt ended so.
    pub(crate) reason: PickReason,
    /// Human-readable detail.
    pub(crate) detail: String,
    /// The object whose surface the camera saw at the grasp centre (ground truth, for the
    /// report only; no policy sees it).
    pub(crate) aimed_at: Option<String>,
    /// The object that was held, if any.
    pub(crate) held: Option<String>,
    /// After a success: where the held object came to rest (`bin2` when placed; `bin1` or
    /// `lost` when it ended elsewhere). Absent for a failure, and in reports from before it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) placed: Option<ObjectLocation>,
    /// empty_bin: objects in bin 2 after this attempt.
    pub(crate) moved: Option<usize>,
    /// Where the visualisation went.
    pub(crate) vis: Option<PathBuf>,
    /// Where the time went.
    pub(crate) timing: AttemptTiming,
    /// Physics invariants broken during the attempt (with `--check-invariants` only).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub(crate) violations: Vec<String>,
}

/// empty_bin: where each object ended up.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub(crate) struct BinOutcome {
    /// Objects resting in bin 2.
    pub(crate) moved: usize,
    /// Objects resting in bin 1.
    pub(crate) left: usize,
    /// Objects anywhere else.
    pub(crate) lost: usize,
    /// Each object's final place.
    pub(crate) locations: BTreeMap<String, ObjectLocation>,
    /// Whether the scene ended on `--give-up-after`'s run of failures (absent in reports
    /// written before it existed).
    #[serde(default)]
    pub(crate) gave_up: bool,
}

/// One scene seed's run.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub(crate) struct SceneRun {
    /// The base seed.
    pub(crate) seed: u64,
    /// Every attempt, in order.
    pub(crate) attempts: Vec<AttemptRecord>,
    /// empty_bin only.
    pub(crate) bin: Option<BinOutcome>,
}

/// Everything `eval --json` reports, and what `report` reads back (the fields that schema
/// version 1 lacked default to empty).
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub(crate) struct EvalResults {
    /// train, test or empty_bin.
    pub(crate) task: Task,
    /// model, random or oracle.
    pub(crate) policy: PolicyKind,
    /// The base seeds run.
    pub(crate) seeds: Vec<u64>,
    /// Pick success over all attempts, with its 95 % Wilson interval.
    pub(crate) success: Rate,
    /// train/test: by object.
    #[serde(default)]
    pub(crate) per_object: Vec<ObjectSummary>,
    /// empty_bin: objects moved per scene (mean ± std over seeds).
    pub(crate) moved: Option<Spread>,
    /// empty_bin: objects left in bin 1 per scene.
    pub(crate) left: Option<Spread>,
    /// empty_bin: objects lost per scene.
    pub(crate) lost: Option<Spread>,
    /// Every scene and attempt.
    pub(crate) runs: Vec<SceneRun>,
    /// Where the time went.
    #[serde(default)]
    pub(crate) timing: TimingSummary,
    /// A signal stopped the run: `runs` holds the scenes finished before it (schema version 2).
    #[serde(default)]
    pub(crate) interrupted: bool,
    /// The episode video that `--record` wrote, as given.
    pub(crate) video: Option<PathBuf>,
    /// The folder of the per-attempt visualisations, when the policy drew any.
    pub(crate) vis_dir: Option<PathBuf>,
}

/// The report of a whole evaluation from its scenes.
pub(crate) fn summarise(
    task: Task,
    policy: PolicyKind,
    seeds: Vec<u64>,
    names: &[String],
    runs: Vec<SceneRun>,
    total_wall: f64,
    interrupted: bool,
) -> EvalResults {
    let all: Vec<&AttemptRecord> = runs.iter().flat_map(|r| &r.attempts).collect();
    let successes = all.iter().filter(|a| a.success).count();
    // A push is an attempt but not a grasp: pick success counts grasps, as VPG's does.
    let grasps = all
        .iter()
        .filter(|a| a.reason != PickReason::Pushed)
        .count();
    let per_object = if task == Task::EmptyBin {
        Vec::new()
    } else {
        names
            .iter()
            .map(|name| {
                let mine: Vec<&&AttemptRecord> = all
                    .iter()
                    .filter(|a| a.object.as_deref() == Some(name))
                    .collect();
                let failures = failure_tally(mine.iter().copied().copied());
                ObjectSummary {
                    object: name.clone(),
                    attempts: mine.len(),
                    successes: mine.iter().filter(|a| a.success).count(),
                    failures,
                }
            })
            .collect()
    };
    let spread_of = |f: fn(&BinOutcome) -> usize| {
        (task == Task::EmptyBin).then(|| {
            let values: Vec<f64> = runs
                .iter()
                .filter_map(|r| r.bin.as_ref())
                .map(|b| f(b) as f64)
                .collect();
            Spread::of(&values)
        })
    };
    let n = all.len().max(1) as f64;
    let mean_of = |f: fn(&AttemptTiming) -> f64| all.iter().map(|a| f(&a.timing)).sum::<f64>() / n;
    let walls: Vec<f64> = all.iter().map(|a| a.timing.wall).collect();
    EvalResults {
        task,
        policy,
        seeds,
        success: Rate::new(successes, grasps),
        per_object,
        moved: spread_of(|b| b.moved),
        left: spread_of(|b| b.left),
        lost: spread_of(|b| b.lost),
        timing: TimingSummary {
            attempts: all.len(),
            mean: AttemptTiming {
                wall: mean_of(|t| t.wall),
                sim: mean_of(|t| t.sim),
                render: mean_of(|t| t.render),
                network: mean_of(|t| t.network),
            },
            median_wall: median(&walls),
            total_wall,
            workers: 1,
        },
        runs,
        interrupted,
        video: None,
        vis_dir: None,
    }
}

/// Per-object line of the train/test table.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub(crate) struct ObjectSummary {
    /// Object name.
    pub(crate) object: String,
    /// Its attempts over all seeds.
    pub(crate) attempts: usize,
    /// Its successes.
    pub(crate) successes: usize,
    /// Failure reasons and how often each happened.
    pub(crate) failures: FailureTally,
}

/// The failure reasons of a set of attempts.
fn failure_tally<'a>(attempts: impl IntoIterator<Item = &'a AttemptRecord>) -> FailureTally {
    FailureTally::of(
        attempts
            .into_iter()
            .filter(|a| !a.success)
            .map(|a| a.reason.name()),
    )
}

/// The human-readable report: a table, the overall rate, and where the time went.
pub(crate) fn report_lines(results: &EvalResults, n_past_action: usize) -> Vec<String> {
    let mut lines = Vec::new();
    let seeds = results
        .seeds
        .iter()
        .map(u64::to_string)
        .collect::<Vec<_>>()
        .join(",");
    let suppression = if n_past_action == 0 {
        String::new()
    } else {
        format!(", n_past_action {n_past_action}")
    };
    let policy = results.policy.name();
    let task = results.task.name();
    lines.push(format!(
        "eval --task {task}, policy {policy}, seed {seeds}{suppression}"
    ));
    if results.task == Task::EmptyBin {
        lines.push(format!(
            "{:>6} {:>8} {:>9} {:>6} {:>5} {:>5}  failures",
            "seed", "attempts", "successes", "moved", "left", "lost"
        ));
        for run in &results.runs {
            let Some(bin) = &run.bin else { continue };
            lines.push(format!(
                "{:>6} {:>8} {:>9} {:>6} {:>5} {:>5}  {}",
                run.seed,
                run.attempts.len(),
                run.attempts.iter().filter(|a| a.success).count(),
                bin.moved,
                bin.left,
                bin.lost,
                failure_tally(&run.attempts).describe()
            ));
        }
        if let (Some(moved), Some(lost)) = (&results.moved, &results.lost) {
            let total = results.runs[0]
                .bin
                .as_ref()
                .map_or(0, |b| b.locations.len());
            lines.push(format!(
                "objects moved: {:.1} ± {:.1} of {total} (min {}, max {}, over {} scene{}); lost {:.1}",
                moved.mean,
                moved.std,
                moved.min,
                moved.max,
                moved.count,
                if moved.count == 1 { "" } else { "s" },
                lost.mean
            ));
        }
        lines.push(format!("pick success: {}", results.success.describe()));
    } else {
        let width = results
            .per_object
            .iter()
            .map(|o| o.object.len())
            .max()
            .unwrap_or(6)
            .max(6);
        lines.push(format!(
            "{:<width$} {:>8} {:>9}  failures",
            "object", "attempts", "successes"
        ));
        for o in &results.per_object {
            lines.push(format!(
                "{:<width$} {:>8} {:>9}  {}",
                o.object,
                o.attempts,
                o.successes,
                o.failures.describe()
            ));
        }
        lines.push(format!("success rate: {}", results.success.describe()));
    }
    let (pushed, unverified): (Vec<&AttemptRecord>, Vec<&AttemptRecord>) = results
        .runs
        .iter()
        .flat_map(|r| &r.attempts)
        .filter(|a| a.verified == Some(false))
        .partition(|a| a.reason == PickReason::Pushed);
    if !unverified.is_empty() {
        // These are where a failure is most likely (docs/evaluation.md, "Verification").
        lines.push(format!(
            "unverified: {} executed the argmax as nothing passed verification; {} succeeded",
            counted(unverified.len(), "attempt"),
            unverified.iter().filter(|a| a.success).count()
        ));
    }
    if !pushed.is_empty() {
        lines.push(format!(
            "pushed: {} pushed where nothing passed verification; pick success leaves them out",
            counted(pushed.len(), "attempt"),
        ));
    }
    let t = &results.timing;
    lines.push(format!(
        "per attempt: {:.2} s wall (median {:.2}) = sim {:.2} + render {:.3} + network {:.3} + other {:.3}; total {:.1} s{}",
        t.mean.wall,
        t.median_wall,
        t.mean.sim,
        t.mean.render,
        t.mean.network,
        (t.mean.wall - t.mean.sim - t.mean.render - t.mean.network).max(0.0),
        t.total_wall,
        match t.workers {
            0 | 1 => String::new(),
            n => format!(
                ", {:.2} s per attempt with {n} at once",
                t.total_wall / t.attempts.max(1) as f64
            ),
        }
    ));
    lines
}

/// Mean per-attempt time.
#[derive(Debug, Clone, Copy, Default, serde::Serialize, serde::Deserialize)]
pub(crate) struct TimingSummary {
    /// Attempts timed.
    pub(crate) attempts: usize,
    /// Mean of each part.
    pub(crate) mean: AttemptTiming,
    /// Median wall seconds.
    pub(crate) median_wall: f64,
    /// Wall seconds of the whole evaluation.
    pub(crate) total_wall: f64,
    /// Threads that ran scenes (or single-object attempts) side by side; 1 when they ran one
    /// after another.
    #[serde(default = "one_worker")]
    pub(crate) workers: usize,
}

fn one_worker() -> usize {
    1
}
