//! An evaluation report as printed: the per-object or per-scene table, VPG's metrics for
//! scenes, the unverified and pushed attempts, and where the time went.

use super::eval_report::{
    failure_tally, AttemptRecord, EvalResults, PushRecord, Task, TimingSummary,
};
use crate::named::{counted, Named};
use crate::sim::pick::PickReason;

/// The human-readable report: a table, the overall rate, and where the time went.
pub(crate) fn report_lines(results: &EvalResults, n_past_action: usize) -> Vec<String> {
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
    let mut lines = vec![format!(
        "eval --task {task}, policy {policy}, seed {seeds}{suppression}"
    )];
    match results.task {
        Task::EmptyBin => lines.extend(scene_table(results)),
        Task::Scenes => lines.extend(case_table(results)),
        Task::Train | Task::Test => lines.extend(object_table(results)),
    }
    lines.extend(unverified_lines(results));
    lines.push(timing_line(&results.timing));
    if results.task == Task::Scenes {
        lines.extend(vpg_metric_lines(results));
    }
    lines
}

/// scenes: a line per run, then a line per case with VPG's metrics.
fn case_table(results: &EvalResults) -> Vec<String> {
    let width = results
        .cases
        .iter()
        .map(|c| c.scene.len())
        .max()
        .unwrap_or(5)
        .max(5);
    let mut lines = vec![format!(
        "{:<width$} {:>6} {:>7} {:>6} {:>6} {:>6}  ended",
        "scene", "seed", "actions", "grasps", "pushes", "moved"
    )];
    for run in &results.runs {
        let Some(bin) = &run.bin else { continue };
        let grasps = run.attempts.iter().filter(|a| a.is_grasp()).count();
        lines.push(format!(
            "{:<width$} {:>6} {:>7} {:>6} {:>6} {:>3}/{:<2}  {}",
            run.scene.as_deref().unwrap_or(""),
            run.seed,
            run.attempts.len(),
            grasps,
            run.attempts.len() - grasps,
            bin.moved,
            bin.locations.len(),
            match (bin.left, bin.lost, bin.gave_up) {
                (0, 0, _) => "cleared".to_owned(),
                (_, _, true) => "gave up".to_owned(),
                (0, lost, false) => format!("{lost} lost outside the bins"),
                (left, _, false) => format!("{left} left at the attempt budget"),
            }
        ));
    }
    let percent =
        |v: Option<f64>| v.map_or_else(|| "–".to_owned(), |v| format!("{:.1} %", 100.0 * v));
    lines.push(format!(
        "{:<width$} {:>10} {:>13} {:>17} {:>11}",
        "case", "completion", "grasp success", "action efficiency", "grasp share"
    ));
    for case in &results.cases {
        lines.push(format!(
            "{:<width$} {:>10} {:>13} {:>17} {:>11}",
            case.scene,
            percent(Some(case.completion)),
            percent(case.grasp_success),
            percent(case.action_efficiency),
            percent(case.grasp_share)
        ));
    }
    lines
}

/// scenes: the three closing lines, VPG's metrics as means over the cases.
fn vpg_metric_lines(results: &EvalResults) -> Vec<String> {
    let Some(mean) = results.cases.last() else {
        return Vec::new();
    };
    let cases = counted(results.cases.len() - 1, "case");
    let percent = |v: Option<f64>| {
        v.map_or_else(
            || "– (no run completed)".to_owned(),
            |v| format!("{:.1} %", 100.0 * v),
        )
    };
    vec![
        format!(
            "completion: {} of {} runs cleared, mean over {cases} = {}",
            mean.completed,
            mean.runs,
            percent(Some(mean.completion))
        ),
        format!(
            "grasp success: per completed run, mean over {cases} = {}",
            percent(mean.grasp_success)
        ),
        format!(
            "action efficiency: objects / actions per completed run, mean over {cases} = {}",
            percent(mean.action_efficiency)
        ),
    ]
}

/// empty_bin: a line per scene, the objects moved over the scenes and the pick success.
fn scene_table(results: &EvalResults) -> Vec<String> {
    let mut lines = vec![format!(
        "{:>6} {:>8} {:>9} {:>6} {:>5} {:>5}  failures",
        "seed", "attempts", "successes", "moved", "left", "lost"
    )];
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
    lines
}

/// train/test: a line per object and the success rate.
fn object_table(results: &EvalResults) -> Vec<String> {
    let width = results
        .per_object
        .iter()
        .map(|o| o.object.len())
        .max()
        .unwrap_or(6)
        .max(6);
    let mut lines = vec![format!(
        "{:<width$} {:>8} {:>9}  failures",
        "object", "attempts", "successes"
    )];
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
    lines
}

/// The attempts that executed a grasp (or a push) nothing verified, when there were any.
fn unverified_lines(results: &EvalResults) -> Vec<String> {
    let mut lines = Vec::new();
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
    lines
}

/// Where the time of an attempt went.
fn timing_line(t: &TimingSummary) -> String {
    format!(
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
    )
}

// Printing a push lives with the other printed lines.
impl PushRecord {
    /// "moved Block4 42 mm, Block6 9 mm", or "moved nothing".
    pub(crate) fn describe(&self) -> String {
        match self.moved.is_empty() {
            true => "moved nothing".to_owned(),
            false => format!(
                "moved {}",
                self.moved
                    .iter()
                    .map(|(name, mm)| format!("{name} {mm:.0} mm"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        }
    }
}
