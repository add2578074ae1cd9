//! The report's evaluation section: every report `eval` kept under DATA/reports, grouped by task
//! and then by the settings that make runs comparable (seeds, attempts, objects:
//! present::kept_reports), the model beside the baselines run with the same settings, then each
//! report's table, visualisations and video. Runs with other settings are never put side by side:
//! each group names its settings.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::Context as _;
use serde::Deserialize;

use super::files::Files;
use super::html::{esc, missing};
use crate::assets::BUNDLED_PREFIX;
use crate::metrics::{FailureTally, Spread};
use crate::named::Named;
use crate::policy::PolicyKind;
use crate::present::eval_report::{AttemptRecord, EvalResults, ObjectSummary, SceneRun, Task};
use crate::present::kept_reports::{Comparable, DEFAULT_MAX_ATTEMPTS};

/// Per-attempt visualisations shown per report; the rest stay in their folder.
const VIS_SHOWN: usize = 6;

/// A kept `graspmap.eval` report: its results as `eval` writes them, and the two settings of
/// its run the page needs (other fields are ignored).
#[derive(Debug, Deserialize)]
struct Kept {
    schema: String,
    #[serde(default)]
    git_commit: String,
    config: RunSettings,
    results: EvalResults,
}

/// Where the evaluation ran, what it recorded, and the settings that decide what it can be
/// compared with, from the report's resolved config.
#[derive(Debug, Deserialize)]
struct RunSettings {
    global: RunGlobal,
    #[serde(default)]
    record: Option<PathBuf>,
    /// The whole sweep's seeds (older reports: the results' seeds).
    #[serde(default)]
    seeds: Option<Vec<u64>>,
    #[serde(default)]
    max_attempts: Option<u32>,
    #[serde(default)]
    give_up_after: Option<u32>,
    #[serde(default)]
    objects: Vec<String>,
    #[serde(default)]
    shard: Option<String>,
}

#[derive(Debug, Deserialize)]
struct RunGlobal {
    data: PathBuf,
    #[serde(default = "bundled_objects")]
    objects_dir: PathBuf,
    #[serde(default = "bundled_split")]
    split_path: PathBuf,
}

fn bundled_objects() -> PathBuf {
    PathBuf::from(format!("{BUNDLED_PREFIX}objects"))
}

fn bundled_split() -> PathBuf {
    PathBuf::from(format!("{BUNDLED_PREFIX}objects/split.json"))
}

/// One kept report, read and checked.
struct Entry {
    path: PathBuf,
    file_name: String,
    task: Task,
    policy: PolicyKind,
    settings: Comparable,
    report: Kept,
}

/// Reads every `eval_*.json` under `DATA/reports`, in name order.
fn read_kept(dir: &Path) -> anyhow::Result<Vec<Entry>> {
    let Ok(listing) = std::fs::read_dir(dir) else {
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
    paths.into_iter().map(|path| read_one(&path)).collect()
}

fn read_one(path: &Path) -> anyhow::Result<Entry> {
    let fix = "delete it, or run that evaluation again";
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("reading the eval report {}", path.display()))?;
    let report: Kept = serde_json::from_str(&text).map_err(|e| {
        anyhow::anyhow!(
            "{} is not a graspmap eval report ({e}); {fix}",
            path.display()
        )
    })?;
    if !matches!(
        report.schema.as_str(),
        "graspmap.eval/1" | "graspmap.eval/2"
    ) {
        anyhow::bail!(
            "{}: unknown schema '{}'; {fix}",
            path.display(),
            report.schema
        );
    }
    let (task, policy) = (report.results.task, report.results.policy);
    let config = &report.config;
    let settings = Comparable::new(
        task,
        config.seeds.as_deref().unwrap_or(&report.results.seeds),
        config.max_attempts.unwrap_or(DEFAULT_MAX_ATTEMPTS),
        config.give_up_after.unwrap_or(0),
        &config.global.objects_dir,
        &config.global.split_path,
        &config.objects,
        config.shard.clone(),
    );
    Ok(Entry {
        path: path.to_path_buf(),
        file_name: path
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned()),
        task,
        policy,
        settings,
        report,
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

/// The whole section.
pub(crate) fn evals_section(data_dir: &Path, files: &mut Files) -> anyhow::Result<String> {
    let mut html = String::from("<h2>Evaluations</h2>\n");
    let entries = read_kept(&data_dir.join("reports"))?;
    if entries.is_empty() {
        html.push_str(&missing(
            "No evaluation yet",
            "graspmap eval --task train (then --task test, --task empty_bin, and --policy random or oracle for the baselines)",
        ));
        return Ok(html);
    }
    for &task in Task::ALL {
        let mut mine: Vec<&Entry> = entries.iter().filter(|e| e.task == task).collect();
        if mine.is_empty() {
            html.push_str(&missing(
                &format!("No {} evaluation yet", task.name()),
                &format!("graspmap eval --task {}", task.name()),
            ));
            continue;
        }
        let _ = writeln!(html, "<h3>Task {}</h3>", esc(task.name()));
        // One group per set of comparable settings: the defaults first, then in name order.
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
        let several = groups.len() > 1;
        for mut group in groups {
            group.sort_by_key(|e| PolicyKind::ALL.iter().position(|&p| p == e.policy));
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
                html.push_str(&details(entry, data_dir, files)?);
            }
        }
    }
    Ok(html)
}

/// The policies side by side: success with its Wilson interval (and empty_bin's objects moved).
fn comparison(task: Task, entries: &[&Entry], files: &mut Files) -> anyhow::Result<String> {
    let bin = task == Task::EmptyBin;
    let mut html = String::from(
        "<table><tr><th>policy</th><th>seeds</th><th>pick success</th><th>95 % Wilson interval</th>",
    );
    if bin {
        html.push_str("<th>objects moved per scene</th><th>lost</th>");
    }
    html.push_str("<th>report</th><th>commit</th></tr>\n");
    for entry in entries {
        let r = &entry.report.results;
        let s = &r.success;
        let link = files.copy(&entry.path, &format!("reports/{}", entry.file_name))?;
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
        if bin {
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
    for policy in absent.into_iter().filter(|_| settings.shard.is_none()) {
        html.push_str(&missing(
            &format!("No {policy} run of {}{with} yet", task.name()),
            &format!(
                "graspmap eval --task {} --policy {policy}{flags}",
                task.name()
            ),
        ));
    }
    Ok(html)
}

/// One report's own table, its visualisations (capped) and its video.
fn details(entry: &Entry, data_dir: &Path, files: &mut Files) -> anyhow::Result<String> {
    let r = &entry.report.results;
    let mut html = format!(
        "<h4>{} policy, <code>{}</code></h4>\n",
        esc(entry.policy.name()),
        esc(&entry.path.display().to_string())
    );
    html.push_str(&if entry.task == Task::EmptyBin {
        scene_table(&r.runs)
    } else {
        object_table(&r.per_object)
    });
    let run_data = &entry.report.config.global.data;
    // One folder per kept report (`eval_train_model.json` → `train_model/`), so that runs of
    // one task and policy with other settings keep their own pictures.
    let dir = entry
        .file_name
        .strip_prefix("eval_")
        .and_then(|n| n.strip_suffix(".json"))
        .map_or_else(
            || format!("{}_{}", entry.task.name(), entry.policy.name()),
            str::to_owned,
        );
    let drawn: Vec<(&SceneRun, &AttemptRecord, &PathBuf)> = r
        .runs
        .iter()
        .flat_map(|run| run.attempts.iter().map(move |a| (run, a)))
        .filter_map(|(run, a)| a.vis.as_ref().map(|v| (run, a, v)))
        .collect();
    if !drawn.is_empty() {
        html.push_str("<div class=\"gallery\">\n");
        let mut shown = 0;
        // Spread over the whole run rather than the first few attempts of the first object.
        let picks =
            (0..VIS_SHOWN.min(drawn.len())).map(|k| k * drawn.len() / VIS_SHOWN.min(drawn.len()));
        for (run, attempt, vis) in picks.map(|i| drawn[i]) {
            let Some(found) = locate(vis, run_data, data_dir) else {
                continue;
            };
            let name = found
                .file_name()
                .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
            let prefix = format!("seed{}_", run.seed);
            let name = if name.starts_with(&prefix) {
                name
            } else {
                prefix + &name
            };
            let link = files.copy(&found, &format!("{dir}/{name}"))?;
            let what = attempt.object.as_deref().unwrap_or("scene");
            let outcome = if attempt.success {
                "success"
            } else {
                attempt.reason.name()
            };
            let _ = writeln!(
                html,
                "<figure><img src=\"{}\" width=\"256\" height=\"256\" alt=\"attempt visualisation\"><figcaption>seed {}, {} attempt {}: {}</figcaption></figure>",
                esc(&link),
                run.seed,
                esc(what),
                attempt.attempt,
                esc(outcome)
            );
            shown += 1;
        }
        html.push_str("</div>\n");
        let folder = r.vis_dir.as_ref().map_or_else(
            || "where the report's attempts name them".to_string(),
            |d| format!("in <code>{}</code>", esc(&d.display().to_string())),
        );
        let wanted = VIS_SHOWN.min(drawn.len());
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
            "<p class=\"note\">Showing {shown} of {} attempt visualisations (each bin's rotated image and affordance map, the chosen bin framed); all of them are {folder}.{gone}</p>",
            drawn.len()
        );
    }
    html.push_str(&video(entry, data_dir, &dir, files)?);
    Ok(html)
}

/// The episode video, if the evaluation recorded one: `<video>` for MP4, `<img>` for GIF.
fn video(entry: &Entry, data_dir: &Path, dir: &str, files: &mut Files) -> anyhow::Result<String> {
    let recorded = entry
        .report
        .results
        .video
        .as_ref()
        .or(entry.report.config.record.as_ref());
    let Some(recorded) = recorded else {
        // A sweep of several seeds has no episode video: --record films one scene.
        return Ok(
            if entry.task == Task::EmptyBin && entry.settings.seeds.len() == 1 {
                missing(
                    "No episode video of this run",
                    &format!(
                        "graspmap eval --task empty_bin --policy {}{} --record episode.mp4",
                        entry.policy.name(),
                        entry.settings.eval_flags()
                    ),
                )
            } else {
                String::new()
            },
        );
    };
    let Some(found) = locate(recorded, &entry.report.config.global.data, data_dir) else {
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
        &format!("{dir}/episode.{}", if gif { "gif" } else { "mp4" }),
    )?;
    Ok(if gif {
        format!(
            "<p><img class=\"video\" src=\"{}\" alt=\"episode video\"></p>\n",
            esc(&link)
        )
    } else {
        format!(
            "<p><video controls preload=\"metadata\" src=\"{}\">episode video (H.264 MP4)</video></p>\n",
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
