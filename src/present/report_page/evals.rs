//! The report's folded evaluation section: every report `eval` kept under DATA/reports, grouped
//! by task and then by the settings that make runs comparable (seeds, attempts, objects:
//! present::kept_reports), the model beside the baselines run with the same settings, then each
//! report's table, pictures and video. Runs with other settings are never put side by side: each
//! group names its settings. The first screen's summary (summary.rs) picks from the same groups.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use super::files::Files;
use super::html::{esc, missing};
use super::kept::{groups, Entry, Picture};
use crate::metrics::{FailureTally, Spread};
use crate::named::Named;
use crate::policy::PolicyKind;
use crate::present::eval_report::{EvalResults, ObjectSummary, SceneRun, Task};

/// Per-attempt visualisations shown per report; the rest stay in their folder.
const VIS_SHOWN: usize = 6;

/// The whole section, for the reports kept in DATA; `top` is the report whose video the first
/// screen shows (not repeated here).
pub(crate) fn evals_section(
    entries: &[Entry],
    files: &mut Files,
    top: Option<&Path>,
) -> anyhow::Result<String> {
    let mut html = String::new();
    if entries.is_empty() {
        html.push_str(&missing(
            "No evaluation yet (then --task test and --task empty_bin, and the baselines with --policy random and --policy oracle)",
            &files.command("eval --task train"),
        ));
        return Ok(html);
    }
    for &task in Task::ALL {
        let groups = groups(entries.iter().filter(|e| e.task == task));
        if groups.is_empty() && task == Task::Scenes {
            continue;
        }
        if groups.is_empty() {
            html.push_str(&missing(
                &format!("No {} evaluation yet", task.name()),
                &files.command(&format!("eval --task {}", task.name())),
            ));
            continue;
        }
        let _ = writeln!(html, "<h3>Task {}</h3>", esc(task.name()));
        let several = groups.len() > 1;
        for group in groups {
            let settings = &group[0].settings;
            if several || !settings.is_default() {
                let _ = writeln!(
                    html,
                    "<p class=\"note\">Runs with {}{}:</p>",
                    esc(&settings.describe()),
                    if several {
                        " (runs with other settings are listed apart, not compared)"
                    } else {
                        ""
                    }
                );
            }
            html.push_str(&comparison(task, &group, files)?);
            for entry in group {
                let at_top = top == Some(entry.path.as_path());
                html.push_str(&details(entry, files, at_top)?);
            }
        }
    }
    Ok(html)
}

/// The policies side by side: success with its Wilson interval (and empty_bin's objects moved).
fn comparison(task: Task, entries: &[&Entry], files: &mut Files) -> anyhow::Result<String> {
    let bin = task.clears_a_bin();
    let mut html = String::from(
        "<table><tr><th>policy</th><th>seeds</th><th>pick success</th><th>95 % Wilson interval</th>",
    );
    if bin {
        html.push_str("<th>objects moved per scene</th><th>lost</th>");
    }
    if task == Task::Scenes {
        html.push_str("<th>completion</th><th>grasp success</th><th>action efficiency</th>");
    }
    html.push_str("<th>report</th><th>commit</th></tr>\n");
    for entry in entries {
        let r = &entry.report.results;
        let s = &r.success;
        let link = files.copy(&entry.path, &entry.copy_name)?;
        let class = if entry.policy == PolicyKind::Model {
            " class=\"model\""
        } else {
            ""
        };
        let seeds: Vec<String> = r.seeds.iter().map(u64::to_string).collect();
        let _ = write!(
            html,
            "<tr{class}><td>{}</td><td>{}</td><td class=\"num\">{}/{} = {:.1} %</td><td class=\"num\">{:.1}–{:.1} %</td>",
            esc(entry.policy.name()),
            esc(&seeds.join(", ")),
            s.successes,
            s.trials,
            100.0 * s.rate,
            100.0 * s.wilson_low,
            100.0 * s.wilson_high
        );
        html.push_str(&clearing_cells(task, r));
        let interrupted = if r.interrupted { " (interrupted)" } else { "" };
        let _ = writeln!(
            html,
            "<td><a href=\"{}\">{}</a>{interrupted}</td><td><code>{}</code></td></tr>",
            esc(&link),
            esc(&entry.file_name),
            esc(&entry.report.git_commit)
        );
    }
    html.push_str("</table>\n");
    let absent: Vec<&str> = PolicyKind::ALL
        .iter()
        .filter(|p| !entries.iter().any(|e| e.policy == **p))
        .map(|p| p.name())
        .collect();
    let settings = &entries[0].settings;
    let (with, flags) = match settings.is_default() {
        true => ("", String::new()),
        false => (" with these settings", settings.eval_flags()),
    };
    // A shard's missing baselines are runs of the whole sweep; the shard is one part of it.
    // A scenes run's baselines need its scene files, which the row does not know.
    let hints = settings.shard.is_none() && task != Task::Scenes;
    for policy in absent.into_iter().filter(|_| hints) {
        html.push_str(&missing(
            &format!("No {policy} run of {}{with} yet", task.name()),
            &files.command(&format!(
                "eval --task {} --policy {policy}{flags}",
                task.name()
            )),
        ));
    }
    Ok(html)
}

/// empty_bin and scenes: the objects moved and lost; scenes: VPG's three means.
fn clearing_cells(task: Task, r: &EvalResults) -> String {
    let mut html = String::new();
    if task.clears_a_bin() {
        let spread = |s: &Option<Spread>| {
            s.as_ref().map_or("–".into(), |s| {
                format!("{:.1} ± {:.1} ({}–{})", s.mean, s.std, s.min, s.max)
            })
        };
        let _ = write!(
            html,
            "<td class=\"num\">{}</td><td class=\"num\">{}</td>",
            spread(&r.moved),
            r.lost
                .as_ref()
                .map_or("–".into(), |l| format!("{:.1}", l.mean))
        );
    }
    if task == Task::Scenes {
        let percent = |v: Option<f64>| v.map_or("–".into(), |v| format!("{:.1} %", 100.0 * v));
        let mean = r.cases.last();
        let _ = write!(
            html,
            "<td class=\"num\">{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td>",
            percent(mean.map(|m| m.completion)),
            percent(mean.and_then(|m| m.grasp_success)),
            percent(mean.and_then(|m| m.action_efficiency))
        );
    }
    html
}

/// One report's own table, its pictures (capped) and its video (unless the first screen shows
/// it).
pub(super) fn details(
    entry: &Entry,
    files: &mut Files,
    video_at_top: bool,
) -> anyhow::Result<String> {
    let r = &entry.report.results;
    let mut html = format!(
        "<h4>{} policy, <code>{}</code></h4>\n",
        esc(entry.policy.name()),
        esc(&entry.path.display().to_string())
    );
    html.push_str(&match entry.task {
        Task::EmptyBin => scene_table(&r.runs),
        Task::Scenes => case_tables(r),
        Task::Train | Task::Test => object_table(&r.per_object),
    });
    html.push_str(&gallery(entry, files)?);
    if video_at_top {
        html.push_str("<p class=\"note\">Its episode video is at the top of the page.</p>\n");
    } else {
        html.push_str(&video(entry, files)?);
    }
    Ok(html)
}

/// A few of the report's per-attempt pictures, spread over the whole run.
fn gallery(entry: &Entry, files: &mut Files) -> anyhow::Result<String> {
    let r = &entry.report.results;
    let drawn = entry.pictures();
    if drawn.is_empty() {
        return Ok(String::new());
    }
    let mut html = String::from("<div class=\"gallery\">\n");
    let wanted = VIS_SHOWN.min(drawn.len());
    let mut shown = 0;
    // Spread over the whole run rather than the first few attempts of the first object.
    for picture in (0..wanted).map(|k| &drawn[k * drawn.len() / wanted]) {
        if let Some(figure) = figure(entry, picture, files, "")? {
            html.push_str(&figure);
            shown += 1;
        }
    }
    html.push_str("</div>\n");
    let folder = r.vis_dir.as_ref().map_or_else(
        || "where the report's attempts name them".to_string(),
        |d| format!("in <code>{}</code>", esc(&d.display().to_string())),
    );
    let gone = if shown < wanted {
        format!(
            " {} of those chosen are no longer on disk: run the evaluation again to draw them.",
            wanted - shown
        )
    } else {
        String::new()
    };
    let _ = writeln!(
        html,
        "<p class=\"note\">Showing {shown} of {} attempt pictures; all of them are {folder}.{gone} {PICTURE_KEY}</p>",
        drawn.len()
    );
    Ok(html)
}

/// An attempt's picture as a `<figure>` (at its own size, class `affordance`), copied into the
/// entry's folder; `None` when the file is no longer on disk.
pub(super) fn figure(
    entry: &Entry,
    picture: &Picture,
    files: &mut Files,
    key: &str,
) -> anyhow::Result<Option<String>> {
    let Some(found) = entry.locate(&picture.path) else {
        return Ok(None);
    };
    let name = found
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    let prefix = format!("seed{}_", picture.seed);
    let name = if name.starts_with(&prefix) {
        name
    } else {
        prefix + &name
    };
    let link = files.copy(&found, &format!("{}/{name}", entry.folder))?;
    // Pictures of older runs have other sizes: the page takes each one's own.
    let size = image::image_dimensions(&found).map_or_else(
        |_| String::new(),
        |(w, h)| format!(" width=\"{w}\" height=\"{h}\""),
    );
    Ok(Some(format!(
        "<figure><img class=\"affordance\" src=\"{}\"{size} alt=\"the network's scores over the camera's image\"><figcaption>{} {}, seed {}, {} attempt {}: {}.{key}</figcaption></figure>\n",
        esc(&link),
        esc(entry.task.name()),
        esc(entry.policy.name()),
        picture.seed,
        esc(&picture.what),
        picture.attempt,
        esc(&picture.outcome)
    )))
}

/// What an attempt's picture shows, said once under each gallery.
const PICTURE_KEY: &str = "Each shows the network's scores as heat over the camera's image: left, the best of the 8 angles at each pixel, with the executed grasp drawn as the open gripper (green pads, red closing line, to scale); right, each angle's map in the image's own frame, the chosen angle framed. The colours span the picture's own lowest to highest score on a square-root scale, as its colour bar says.";

/// The episode video, if the evaluation recorded one: `<video>` for MP4, `<img>` for GIF; a
/// line naming the command when it did not, or the file is gone.
pub(super) fn video(entry: &Entry, files: &mut Files) -> anyhow::Result<String> {
    let Some(recorded) = entry.recorded_video() else {
        // A sweep of several seeds has no episode video: --record films one scene.
        return Ok(
            if entry.task == Task::EmptyBin && entry.settings.seeds.len() == 1 {
                missing(
                    "No episode video of this run",
                    &files.command(&format!(
                        "eval --task empty_bin --policy {}{} --record {}",
                        entry.policy.name(),
                        entry.settings.eval_flags(),
                        files.video_path(&format!("empty_bin_{}.mp4", entry.policy.name()))
                    )),
                )
            } else {
                String::new()
            },
        );
    };
    let Some(found) = entry.locate(recorded) else {
        return Ok(format!(
            "<p class=\"missing\">The episode video {} is gone: rerun the evaluation with <code>--record</code>.</p>\n",
            esc(&recorded.display().to_string())
        ));
    };
    let gif = found
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gif"));
    let link = files.copy(
        &found,
        &format!(
            "{}/episode.{}",
            entry.folder,
            if gif { "gif" } else { "mp4" }
        ),
    )?;
    Ok(if gif {
        format!(
            "<img class=\"video\" src=\"{}\" alt=\"episode video\">\n",
            esc(&link)
        )
    } else {
        format!(
            "<video controls preload=\"metadata\" src=\"{}\">episode video (H.264 MP4)</video>\n",
            esc(&link)
        )
    })
}

/// train/test: attempts, successes and failure reasons per object.
fn object_table(rows: &[ObjectSummary]) -> String {
    let mut html = String::from(
        "<table><tr><th>object</th><th>attempts</th><th>successes</th><th>failures</th></tr>\n",
    );
    for o in rows {
        let _ = writeln!(
            html,
            "<tr><td>{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td><td>{}</td></tr>",
            esc(&o.object),
            o.attempts,
            o.successes,
            esc(&tally(o.failures.counts()))
        );
    }
    html.push_str("</table>\n");
    html
}

/// empty_bin: attempts, successes, moved, left and lost per scene.
fn scene_table(runs: &[SceneRun]) -> String {
    let mut html = String::from(
        "<table><tr><th>seed</th><th>attempts</th><th>successes</th><th>moved</th><th>left</th><th>lost</th><th>failures</th></tr>\n",
    );
    for run in runs {
        let mut failures = FailureTally::default();
        for a in run.attempts.iter().filter(|a| !a.success) {
            failures.add(a.reason.name());
        }
        let (moved, left, lost) = run
            .bin
            .as_ref()
            .map_or((0, 0, 0), |b| (b.moved, b.left, b.lost));
        let _ = writeln!(
            html,
            "<tr><td class=\"num\">{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td><td class=\"num\">{moved}</td><td class=\"num\">{left}</td><td class=\"num\">{lost}</td><td>{}</td></tr>",
            run.seed,
            run.attempts.len(),
            run.attempts.iter().filter(|a| a.success).count(),
            esc(&tally(failures.counts()))
        );
    }
    html.push_str("</table>\n");
    html
}

/// scenes: VPG's metrics per case, then every run with its actions, each push with what it
/// moved (where runs fail, pushes are what to look at first).
fn case_tables(results: &EvalResults) -> String {
    let percent = |v: Option<f64>| v.map_or("–".into(), |v| format!("{:.1} %", 100.0 * v));
    let mut html = String::from(
        "<table><tr><th>case</th><th>runs</th><th>completion</th><th>grasp success</th><th>action efficiency</th><th>grasps among actions</th></tr>\n",
    );
    for case in &results.cases {
        let _ = writeln!(
            html,
            "<tr><td>{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td></tr>",
            esc(&case.scene),
            case.runs,
            percent(Some(case.completion)),
            percent(case.grasp_success),
            percent(case.action_efficiency),
            percent(case.grasp_share)
        );
    }
    html.push_str("</table>\n<table><tr><th>case</th><th>seed</th><th>actions, in order</th><th>moved</th></tr>\n");
    for run in &results.runs {
        let actions: Vec<String> = run
            .attempts
            .iter()
            .map(|a| match (&a.push, a.success) {
                (Some(push), _) => format!("push: {}", push.describe()),
                (None, true) => format!("grasp ✓ {}", a.held.as_deref().unwrap_or("")),
                (None, false) => format!("grasp ✗ {}", a.reason.name()),
            })
            .collect();
        let (moved, of) = run
            .bin
            .as_ref()
            .map_or((0, 0), |b| (b.moved, b.locations.len()));
        let _ = writeln!(
            html,
            "<tr><td>{}</td><td class=\"num\">{}</td><td>{}</td><td class=\"num\">{moved}/{of}</td></tr>",
            esc(run.scene.as_deref().unwrap_or("")),
            run.seed,
            esc(&actions.join(" · "))
        );
    }
    html.push_str("</table>\n");
    html
}

fn tally(failures: &BTreeMap<String, usize>) -> String {
    if failures.is_empty() {
        return "–".into();
    }
    failures
        .iter()
        .map(|(reason, n)| format!("{reason} ×{n}"))
        .collect::<Vec<_>>()
        .join(", ")
}
