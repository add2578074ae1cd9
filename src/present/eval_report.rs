//! What an evaluation reports: the attempt records, per-object and per-scene tables, Wilson
//! intervals and timings, as JSON (`graspmap.eval/2`) and as printed lines.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::Context as _;
use serde::de::DeserializeOwned;
use serde::Serialize;
use serde_json::Value;

use crate::grasp::PixelGrasp;
use crate::metrics::{median, FailureTally, Rate, Spread};
use crate::model::maps::Choice;
use crate::named::{named_enum, Named};
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
        /// Scene files placed as listed (--scenes), each cleared as in empty_bin; VPG's metrics.
        Scenes = "scenes", "scene files placed as listed (--scenes), each cleared as in empty_bin; VPG's metrics",
    }
}

impl Task {
    /// The seed a run without `--seed` uses: 2 for empty_bin, 0 otherwise (the reference's).
    pub(crate) fn default_seed(self) -> u64 {
        match self {
            Task::EmptyBin => DEFAULT_EMPTY_BIN_SEED,
            Task::Train | Task::Test | Task::Scenes => 0,
        }
    }

    /// Whether a run clears a bin of several objects (empty_bin, scenes), rather than picking
    /// one object alone per attempt.
    pub(crate) fn clears_a_bin(self) -> bool {
        matches!(self, Task::EmptyBin | Task::Scenes)
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
    /// A push: where it went and what it moved (absent for grasps).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) push: Option<PushRecord>,
    /// Where the time went.
    pub(crate) timing: AttemptTiming,
    /// Physics invariants broken during the attempt (with `--check-invariants` only).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub(crate) violations: Vec<String>,
}

/// A push as executed, and what it moved.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub(crate) struct PushRecord {
    /// Start of the stroke (world x, y, m).
    pub(crate) start: [f32; 2],
    /// Its end.
    pub(crate) end: [f32; 2],
    /// Each object that moved more than a few millimetres, with how far (mm), farthest first.
    pub(crate) moved: Vec<(String, f32)>,
}

impl PushRecord {
    /// Whether the push changed the scene, as VPG's give-up rule asks: some object moved.
    pub(crate) fn changed_the_scene(&self) -> bool {
        !self.moved.is_empty()
    }
}

impl AttemptRecord {
    /// Whether the attempt counts as a failed action in VPG's give-up rule: a grasp that held
    /// nothing, or a push that moved nothing.
    pub(crate) fn failed_action(&self) -> bool {
        !self.success
            && !self
                .push
                .as_ref()
                .is_some_and(PushRecord::changed_the_scene)
    }

    /// Whether the attempt was a grasp (VPG's metrics count pushes as actions, not grasps).
    pub(crate) fn is_grasp(&self) -> bool {
        self.reason != PickReason::Pushed
    }
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
    /// scenes: the scene file's name (its stem).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) scene: Option<String>,
    /// The base seed.
    pub(crate) seed: u64,
    /// Every attempt, in order.
    pub(crate) attempts: Vec<AttemptRecord>,
    /// empty_bin and scenes.
    pub(crate) bin: Option<BinOutcome>,
}

/// VPG's metrics of one case (scene file) or of their mean, as its evaluate.py computes them.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub(crate) struct CaseMetrics {
    /// The scene's name, or "mean" over the cases.
    pub(crate) scene: String,
    /// Runs (seeds) of the case.
    pub(crate) runs: usize,
    /// Runs that moved every placed object before giving up.
    pub(crate) completed: usize,
    /// completed / runs.
    pub(crate) completion: f64,
    /// Successful grasps / grasp attempts of each completed run, averaged over completed runs
    /// (`None` when no run completed).
    pub(crate) grasp_success: Option<f64>,
    /// Objects / actions (pushes too) of each completed run, averaged.
    pub(crate) action_efficiency: Option<f64>,
    /// Grasps / actions of each completed run, averaged.
    pub(crate) grasp_share: Option<f64>,
}

impl CaseMetrics {
    /// The metrics of one case's runs.
    pub(crate) fn of(scene: &str, runs: &[&SceneRun]) -> Self {
        let completed: Vec<&&SceneRun> = runs
            .iter()
            .filter(|r| {
                r.bin
                    .as_ref()
                    .is_some_and(|b| b.left == 0 && b.lost == 0 && !b.locations.is_empty())
            })
            .collect();
        let mean = |f: &dyn Fn(&SceneRun) -> f64| {
            (!completed.is_empty())
                .then(|| completed.iter().map(|r| f(r)).sum::<f64>() / completed.len() as f64)
        };
        let actions = |r: &SceneRun| r.attempts.len().max(1) as f64;
        let grasps = |r: &SceneRun| r.attempts.iter().filter(|a| a.is_grasp()).count() as f64;
        Self {
            scene: scene.to_owned(),
            runs: runs.len(),
            completed: completed.len(),
            completion: completed.len() as f64 / runs.len().max(1) as f64,
            grasp_success: mean(&|r| {
                let held = r
                    .attempts
                    .iter()
                    .filter(|a| a.is_grasp() && a.success)
                    .count();
                held as f64 / grasps(r).max(1.0)
            }),
            action_efficiency: mean(&|r| {
                r.bin.as_ref().map_or(0, |b| b.locations.len()) as f64 / actions(r)
            }),
            grasp_share: mean(&|r| grasps(r) / actions(r)),
        }
    }

    /// The mean of each metric over `cases` (each case weighs the same, as in VPG's tables);
    /// a metric no case has stays `None`.
    pub(crate) fn mean(cases: &[CaseMetrics]) -> Self {
        let of = |f: fn(&CaseMetrics) -> Option<f64>| {
            let values: Vec<f64> = cases.iter().filter_map(f).collect();
            (!values.is_empty()).then(|| values.iter().sum::<f64>() / values.len() as f64)
        };
        Self {
            scene: "mean".to_owned(),
            runs: cases.iter().map(|c| c.runs).sum(),
            completed: cases.iter().map(|c| c.completed).sum(),
            completion: of(|c| Some(c.completion)).unwrap_or(0.0),
            grasp_success: of(|c| c.grasp_success),
            action_efficiency: of(|c| c.action_efficiency),
            grasp_share: of(|c| c.grasp_share),
        }
    }
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
    /// scenes: VPG's metrics per scene file, then their mean.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub(crate) cases: Vec<CaseMetrics>,
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
    /// Seconds spent encoding and writing that video (absent without `--record`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) video_encode_s: Option<f64>,
    /// The folder of the per-attempt visualisations, when the policy drew any.
    pub(crate) vis_dir: Option<PathBuf>,
}

/// The schema `eval` writes and its readers accept.
pub(crate) const EVAL_SCHEMA: &str = "graspmap.eval/2";

/// An eval report as `merge`, `eval --resume`, `improve` and `report` read it back: the envelope's
/// commit, the settings they compare, and the results, in the types `eval` writes them with.
/// [`EvalReport::read`] fills nothing in: another schema, or a field missing or of another
/// type, is an error that names the file.
#[derive(Debug, Clone)]
pub(crate) struct EvalReport {
    /// Where it was read from.
    pub(crate) path: PathBuf,
    /// The commit of the binary that wrote it.
    pub(crate) git_commit: String,
    /// The settings of its `config` that readers use.
    pub(crate) config: EvalSettings,
    /// Its whole `config`, as written.
    pub(crate) config_value: Value,
    /// What the evaluation found.
    pub(crate) results: EvalResults,
}

/// The settings of an eval report's `config` that its readers use (`resolved_config` in
/// commands/eval/sweep.rs writes them, among others).
#[derive(Debug, Clone, Serialize, serde::Deserialize)]
pub(crate) struct EvalSettings {
    /// train, test or empty_bin.
    pub(crate) task: Task,
    /// model, random or oracle.
    pub(crate) policy: PolicyKind,
    /// The whole sweep's seeds (a shard's are in `results.seeds`).
    pub(crate) seeds: Vec<u64>,
    /// The objects evaluated.
    pub(crate) objects: Vec<String>,
    /// The global flags.
    pub(crate) global: GlobalSettings,
    /// Failure suppression.
    pub(crate) suppression: SuppressionSettings,
    /// The model's checkpoint by content (model policy only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(crate) checkpoint_sha256: Option<String>,
    /// `I/N` for a shard of the sweep; absent for the whole sweep.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(crate) shard: Option<String>,
    /// empty_bin's most attempts per scene.
    pub(crate) max_attempts: u32,
    /// empty_bin's failures in a row that end a scene (0 = never).
    pub(crate) give_up_after: u32,
    /// The `--record` video, when one was asked for.
    pub(crate) record: Option<PathBuf>,
}

/// The global flags of an eval report's `config` that its readers use.
#[derive(Debug, Clone, PartialEq, Serialize, serde::Deserialize)]
pub(crate) struct GlobalSettings {
    /// The data directory it ran with.
    pub(crate) data: PathBuf,
    /// Where the object models came from.
    pub(crate) objects_dir: PathBuf,
    /// The split file it read.
    pub(crate) split_path: PathBuf,
}

/// Failure suppression in an eval report's `config`, as far as its readers use it.
#[derive(Debug, Clone, Copy, Serialize, serde::Deserialize)]
pub(crate) struct SuppressionSettings {
    /// Actions remembered (`--n-past-action`).
    pub(crate) remember: usize,
}

/// The parts of the envelope that [`EvalReport`] keeps.
#[derive(Serialize, serde::Deserialize)]
struct Envelope {
    git_commit: String,
    config: EvalSettings,
    results: EvalResults,
}

impl EvalReport {
    /// Reads the eval report at `path`; each refusal names the file and ends with `fix`.
    pub(crate) fn read(path: &Path, fix: &str) -> anyhow::Result<Self> {
        let text =
            std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
        let refuse = |why: String| {
            anyhow::anyhow!(
                "{} is not a graspmap eval report ({why}; {fix})",
                path.display()
            )
        };
        let value: Value = serde_json::from_str(&text)
            .map_err(|_| refuse("it does not parse as JSON".to_owned()))?;
        if value["schema"] != EVAL_SCHEMA {
            let schema = &value["schema"];
            return Err(refuse(format!("schema {schema}, expected {EVAL_SCHEMA}")));
        }
        let envelope: Envelope = strict(&value).map_err(refuse)?;
        Ok(Self {
            path: path.to_path_buf(),
            git_commit: envelope.git_commit,
            config: envelope.config,
            config_value: value["config"].clone(),
            results: envelope.results,
        })
    }
}

/// `value` as a `T`, with no field filled in by a default: serialised again, every field it
/// writes must have been in `value` (fields written only when set may be absent).
fn strict<T: DeserializeOwned + Serialize>(value: &Value) -> Result<T, String> {
    let typed: T = serde_json::from_value(value.clone()).map_err(|e| e.to_string())?;
    let written = serde_json::to_value(&typed).map_err(|e| e.to_string())?;
    match defaulted_field(value, &written, "") {
        Some(field) => Err(format!("missing field `{field}`")),
        None => Ok(typed),
    }
}

/// The first field of `written` that `read` lacks, as a path (`results.runs[0].bin.gave_up`).
fn defaulted_field(read: &Value, written: &Value, at: &str) -> Option<String> {
    match (read, written) {
        (Value::Object(read), Value::Object(written)) => written.iter().find_map(|(key, w)| {
            let path = match at {
                "" => key.clone(),
                _ => format!("{at}.{key}"),
            };
            match read.get(key) {
                None => Some(path),
                Some(r) => defaulted_field(r, w, &path),
            }
        }),
        (Value::Array(read), Value::Array(written)) => (read.iter().zip(written).enumerate())
            .find_map(|(i, (r, w))| defaulted_field(r, w, &format!("{at}[{i}]"))),
        _ => None,
    }
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
    let per_object = match task.clears_a_bin() {
        true => Vec::new(),
        false => object_summaries(names, &all),
    };
    let spread_of = |f: fn(&BinOutcome) -> usize| {
        task.clears_a_bin().then(|| {
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
    let cases = match task {
        Task::Scenes => case_metrics(&runs),
        _ => Vec::new(),
    };
    EvalResults {
        cases,
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
        video_encode_s: None,
        vis_dir: None,
    }
}

/// train/test: each object's attempts, successes and failures.
fn object_summaries(names: &[String], all: &[&AttemptRecord]) -> Vec<ObjectSummary> {
    names
        .iter()
        .map(|name| {
            let mine: Vec<&AttemptRecord> = all
                .iter()
                .copied()
                .filter(|a| a.object.as_deref() == Some(name))
                .collect();
            ObjectSummary {
                object: name.clone(),
                attempts: mine.len(),
                successes: mine.iter().filter(|a| a.success).count(),
                failures: failure_tally(mine.iter().copied()),
            }
        })
        .collect()
}

/// VPG's metrics of each scene in the order first run, then their mean.
fn case_metrics(runs: &[SceneRun]) -> Vec<CaseMetrics> {
    let mut names: Vec<&str> = Vec::new();
    for run in runs {
        let name = run.scene.as_deref().unwrap_or("");
        if !names.contains(&name) {
            names.push(name);
        }
    }
    let mut cases: Vec<CaseMetrics> = names
        .iter()
        .map(|&name| {
            let mine: Vec<&SceneRun> = runs
                .iter()
                .filter(|r| r.scene.as_deref().unwrap_or("") == name)
                .collect();
            CaseMetrics::of(name, &mine)
        })
        .collect();
    if !cases.is_empty() {
        cases.push(CaseMetrics::mean(&cases));
    }
    cases
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
pub(crate) fn failure_tally<'a>(
    attempts: impl IntoIterator<Item = &'a AttemptRecord>,
) -> FailureTally {
    FailureTally::of(
        attempts
            .into_iter()
            .filter(|a| !a.success)
            .map(|a| a.reason.name()),
    )
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A one-attempt empty_bin report as `eval` writes it.
    fn written(dir: &Path) -> PathBuf {
        let attempt = AttemptRecord {
            drop_seed: 2,
            attempt: 0,
            object: None,
            grasp: None,
            choice: None,
            verified: None,
            success: false,
            reason: PickReason::Ungraspable,
            detail: "nothing".to_owned(),
            aimed_at: None,
            held: None,
            placed: None,
            moved: Some(0),
            vis: None,
            push: None,
            timing: AttemptTiming::default(),
            violations: Vec::new(),
        };
        let run = SceneRun {
            scene: None,
            seed: 2,
            attempts: vec![attempt],
            bin: Some(BinOutcome {
                moved: 0,
                left: 1,
                lost: 0,
                locations: BTreeMap::new(),
                gave_up: false,
            }),
        };
        let names = ["YcbBanana".to_owned()];
        let results = summarise(
            Task::EmptyBin,
            PolicyKind::Random,
            vec![2],
            &names,
            vec![run],
            1.5,
            false,
        );
        let config = serde_json::json!({
            "global": {
                "data": "data",
                "objects_dir": "bundled:objects",
                "split_path": "bundled:objects/split.json",
                "threads": 1,
            },
            "task": "empty_bin",
            "policy": "random",
            "seeds": [2],
            "objects": names,
            "suppression": {"remember": 0, "sigma_px": 4.0},
            "max_attempts": 25,
            "give_up_after": 0,
            "record": null,
        });
        let path = dir.join("eval.json");
        crate::present::envelope::write_versioned_report(&path, "eval", 2, 2, &config, &results)
            .unwrap();
        path
    }

    /// The report at `path` with `edit` applied to its JSON.
    fn edited(path: &Path, edit: impl FnOnce(&mut Value)) {
        let mut value: Value = serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap();
        edit(&mut value);
        std::fs::write(path, serde_json::to_vec(&value).unwrap()).unwrap();
    }

    #[test]
    fn a_written_report_reads_back_in_its_own_types() {
        let dir = tempfile::tempdir().unwrap();
        let path = written(dir.path());
        let report = EvalReport::read(&path, "fix it").unwrap();
        assert_eq!(report.config.task, Task::EmptyBin);
        assert_eq!(report.config.seeds, [2]);
        assert_eq!(report.config.suppression.remember, 0);
        assert_eq!(report.config.shard, None);
        assert_eq!(report.results.timing.total_wall, 1.5);
        assert_eq!(report.results.runs[0].bin.as_ref().unwrap().left, 1);
        assert_eq!(report.config_value["global"]["threads"], 1);
    }

    #[test]
    fn a_missing_field_is_refused_with_the_file_and_the_field_not_filled_in() {
        let dir = tempfile::tempdir().unwrap();
        let path = written(dir.path());
        // Fields that the types default when absent (a version-1 report's) count as missing.
        for (field, remove) in [
            (
                "results.timing.workers",
                (|v: &mut Value| {
                    v["results"]["timing"]
                        .as_object_mut()
                        .unwrap()
                        .remove("workers")
                }) as fn(&mut Value) -> Option<Value>,
            ),
            ("results.runs[0].bin.gave_up", |v| {
                v["results"]["runs"][0]["bin"]
                    .as_object_mut()
                    .unwrap()
                    .remove("gave_up")
            }),
            ("results.vis_dir", |v| {
                v["results"].as_object_mut().unwrap().remove("vis_dir")
            }),
            ("total_wall", |v| {
                v["results"]["timing"]
                    .as_object_mut()
                    .unwrap()
                    .remove("total_wall")
            }),
            ("remember", |v| {
                v["config"]["suppression"]
                    .as_object_mut()
                    .unwrap()
                    .remove("remember")
            }),
        ] {
            let copy = dir.path().join("copy.json");
            std::fs::copy(&path, &copy).unwrap();
            edited(&copy, |v| {
                remove(v).unwrap();
            });
            let error = EvalReport::read(&copy, "fix it").unwrap_err().to_string();
            assert!(
                error.starts_with(&format!(
                    "{} is not a graspmap eval report (",
                    copy.display()
                )) && error.contains(&format!("`{field}`"))
                    && error.ends_with("; fix it)"),
                "{field}: {error}"
            );
        }
        // Fields written only when set may be absent.
        edited(&path, |v| {
            v["results"]["runs"][0]["attempts"][0]
                .as_object_mut()
                .unwrap()
                .remove("violations");
        });
        assert!(EvalReport::read(&path, "fix it").is_ok());
    }

    /// A run of `actions` ("g" a held grasp, "f" a failed one, "p" a push that moved something),
    /// ending with `left` of `objects` still in bin 1.
    fn run(actions: &str, objects: usize, left: usize) -> SceneRun {
        let attempts = actions
            .chars()
            .enumerate()
            .map(|(i, kind)| AttemptRecord {
                drop_seed: 0,
                attempt: i as u32,
                object: None,
                grasp: None,
                choice: None,
                verified: None,
                success: kind == 'g',
                reason: match kind {
                    'g' => PickReason::Success,
                    'p' => PickReason::Pushed,
                    _ => PickReason::EmptyHand,
                },
                detail: String::new(),
                aimed_at: None,
                held: None,
                placed: None,
                moved: None,
                vis: None,
                push: (kind == 'p').then(|| PushRecord {
                    start: [0.0; 2],
                    end: [0.1, 0.0],
                    moved: vec![("Block4".to_owned(), 40.0)],
                }),
                timing: AttemptTiming::default(),
                violations: Vec::new(),
            })
            .collect();
        let locations = (0..objects)
            .map(|i| {
                let place = if i < left {
                    ObjectLocation::Bin1
                } else {
                    ObjectLocation::Bin2
                };
                (format!("Block{i}"), place)
            })
            .collect();
        SceneRun {
            scene: Some("case".to_owned()),
            seed: 0,
            attempts,
            bin: Some(BinOutcome {
                moved: objects - left,
                left,
                lost: 0,
                locations,
                gave_up: left > 0,
            }),
        }
    }

    #[test]
    fn vpg_metrics_average_over_completed_runs_as_its_evaluate_py_does() {
        // Cleared with a push and a failed grasp: 3 of 4 grasps held, 3 objects in 5 actions.
        let first = run("pggfg", 3, 0);
        // Cleared grasp by grasp.
        let second = run("ggg", 3, 0);
        // Gave up: counts against completion only.
        let third = run("gfffffffffff", 3, 2);
        let metrics = CaseMetrics::of("case", &[&first, &second, &third]);
        assert_eq!((metrics.runs, metrics.completed), (3, 2));
        assert!((metrics.completion - 2.0 / 3.0).abs() < 1e-12);
        assert!((metrics.grasp_success.unwrap() - (0.75 + 1.0) / 2.0).abs() < 1e-12);
        assert!((metrics.action_efficiency.unwrap() - (3.0 / 5.0 + 1.0) / 2.0).abs() < 1e-12);
        assert!((metrics.grasp_share.unwrap() - (4.0 / 5.0 + 1.0) / 2.0).abs() < 1e-12);
        // A push that moved something is an action that did not fail; one that moved nothing
        // counts towards giving up, as VPG's rule has it.
        assert!(!first.attempts[0].failed_action());
        let mut idle = first.attempts[0].clone();
        idle.push.as_mut().unwrap().moved.clear();
        assert!(idle.failed_action());
        let none = CaseMetrics::of("case", &[&third]);
        assert_eq!((none.completion, none.grasp_success), (0.0, None));
        let mean = CaseMetrics::mean(&[metrics, none]);
        assert!((mean.completion - 1.0 / 3.0).abs() < 1e-12);
        assert!((mean.grasp_success.unwrap() - 0.875).abs() < 1e-12);
    }

    #[test]
    fn another_schema_or_no_json_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = written(dir.path());
        edited(&path, |v| v["schema"] = Value::from("graspmap.eval/1"));
        let error = EvalReport::read(&path, "fix it").unwrap_err().to_string();
        assert!(
            error.ends_with(
                "is not a graspmap eval report (schema \"graspmap.eval/1\", expected graspmap.eval/2; fix it)"
            ),
            "{error}"
        );
        std::fs::write(&path, "{").unwrap();
        let error = EvalReport::read(&path, "fix it").unwrap_err().to_string();
        assert!(
            error.contains("(it does not parse as JSON; fix it)"),
            "{error}"
        );
    }
}
