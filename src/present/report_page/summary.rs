//! The report's first screen: one results table (train, test and empty_bin, then each `improve`
//! round's evaluations; the model beside the random and oracle baselines, each cell with its
//! seeds, attempts and 95 % Wilson interval), a warning under any row whose baselines ran with
//! other seeds, attempts or objects, then the episode video and one picture of the network's
//! scores. Everything else on the page is folded below it.

use std::fmt::Write as _;
use std::path::PathBuf;

use super::evals::{figure, video};
use super::files::Files;
use super::html::esc;
use super::improve::Round;
use super::kept::{groups, Entry};
use crate::named::{counted, Named};
use crate::policy::PolicyKind;
use crate::present::eval_report::Task;
use crate::present::kept_reports::{seed_list, Comparable};

/// The baselines, in the table's column order.
const BASELINES: [PolicyKind; 2] = [PolicyKind::Random, PolicyKind::Oracle];

/// One row of the table: a model run (or none yet) and the baselines it is shown beside.
struct Row<'a> {
    task: Task,
    /// What the row is: "train", or "improve round 2: empty_bin".
    label: String,
    model: Option<&'a Entry>,
    /// The settings the row stands for: the model's, or the first group's when there is none.
    settings: Option<&'a Comparable>,
    /// The task's kept reports in DATA, comparable groups first (kept::groups' order).
    pool: Vec<&'a Entry>,
}

impl<'a> Row<'a> {
    /// A baseline's run with the row's settings, or else its run with other settings (to be
    /// shown with a warning), or none.
    fn baseline(&self, policy: PolicyKind) -> Option<(&'a Entry, bool)> {
        let mine = self.pool.iter().filter(|e| e.policy == policy);
        let same = mine
            .clone()
            .find(|e| Some(&e.settings) == self.settings)
            .map(|e| (*e, true));
        // A shard is one part of a sweep: never a row's baseline of its own.
        same.or_else(|| {
            mine.clone()
                .find(|e| e.settings.shard.is_none())
                .map(|e| (*e, false))
        })
    }
}

/// The first screen's HTML, and the kept report whose video it shows (the evaluation section
/// does not repeat it).
pub(crate) fn summary_section(
    main: &[Entry],
    rounds: &[Round],
    files: &mut Files,
) -> anyhow::Result<(String, Option<PathBuf>)> {
    let mut rows = Vec::new();
    for &task in Task::ALL {
        let groups = groups(main.iter().filter(|e| e.task == task));
        // Scene files are the user's own: no row asks for them before they are run.
        if task == Task::Scenes && groups.is_empty() {
            continue;
        }
        let headline = groups
            .iter()
            .find(|g| g.iter().any(|e| e.policy == PolicyKind::Model))
            .or(groups.first());
        let model = headline.and_then(|g| g.iter().find(|e| e.policy == PolicyKind::Model));
        rows.push(Row {
            task,
            label: task.name().to_owned(),
            model: model.copied(),
            settings: headline.map(|g| &g[0].settings),
            pool: groups.iter().flatten().copied().collect(),
        });
    }
    for round in rounds {
        for entry in &round.entries {
            let pool = groups(main.iter().filter(|e| e.task == entry.task));
            rows.push(Row {
                task: entry.task,
                label: format!("{}: {}", round.name, entry.task.name()),
                model: Some(entry),
                settings: Some(&entry.settings),
                pool: pool.into_iter().flatten().collect(),
            });
        }
    }
    let mut html = String::from(
        "<table class=\"results\"><tr><th>task</th><th>model</th><th>random</th><th>oracle</th></tr>\n",
    );
    for row in &rows {
        html.push_str(&table_row(row, files)?);
    }
    html.push_str("</table>\n");
    let (media, top) = first_media(main, rounds, files)?;
    html.push_str(&media);
    Ok((html, top))
}

/// A row, and under it the warning when a baseline ran with other settings.
fn table_row(row: &Row, files: &mut Files) -> anyhow::Result<String> {
    let mut html = format!("<tr><th>{}", esc(&row.label));
    if let Some(settings) = row.settings {
        let _ = write!(
            html,
            "<br><small>{}</small>",
            esc(&what(row.task, settings))
        );
    }
    html.push_str("</th>");
    if row.settings.is_none() {
        let command = files.command(&format!("eval --task {}", row.task.name()));
        let _ = writeln!(
            html,
            "<td class=\"none\" colspan=\"3\">not run yet: <code>{}</code>, and with --policy random and --policy oracle for the baselines</td></tr>",
            esc(&command)
        );
        return Ok(html);
    }
    html.push_str(&match row.model {
        Some(entry) => cell(entry, row.task, files)?,
        None => not_run(row, PolicyKind::Model, files),
    });
    let mut warnings = Vec::new();
    for policy in BASELINES {
        html.push_str(&match row.baseline(policy) {
            Some((entry, true)) => cell(entry, row.task, files)?,
            Some((entry, false)) => {
                let theirs = if row.model.is_some() {
                    "the model"
                } else {
                    "the row's runs"
                };
                warnings.push(match row.settings {
                    Some(mine) => format!(
                        "{} ran with {}, {theirs} with {}: not comparable.",
                        policy.name(),
                        differences(&entry.settings, mine).join(", "),
                        differences(mine, &entry.settings).join(", ")
                    ),
                    None => format!("{} ran with {}.", policy.name(), entry.settings.describe()),
                });
                cell(entry, row.task, files)?.replacen("<td>", "<td class=\"other\">⚠ ", 1)
            }
            None => not_run(row, policy, files),
        });
    }
    html.push_str("</tr>\n");
    for warning in warnings {
        let _ = writeln!(
            html,
            "<tr class=\"warning\"><td colspan=\"4\">⚠ {}</td></tr>",
            esc(&warning)
        );
    }
    Ok(html)
}

/// The settings of `a` that `b` does not share, in words: "seed 7", "at most 3 attempts a scene".
fn differences(a: &Comparable, b: &Comparable) -> Vec<String> {
    let mut words = Vec::new();
    if a.seeds != b.seeds {
        let seeds = if a.seeds.len() == 1 { "seed" } else { "seeds" };
        words.push(format!("{seeds} {}", seed_list(&a.seeds)));
    }
    if a.max_attempts != b.max_attempts {
        let n = a.max_attempts.unwrap_or(0) as usize;
        words.push(format!("at most {} a scene", counted(n, "attempt")));
    }
    if a.give_up_after != b.give_up_after {
        let k = a.give_up_after.unwrap_or(0);
        words.push(match k {
            0 => "no giving up".to_owned(),
            k => format!("giving up after {k} failures in a row"),
        });
    }
    if a.objects_dir != b.objects_dir {
        words.push(format!("objects from {}", a.objects_dir));
    }
    if a.split != b.split {
        words.push(format!("split {}", a.split));
    }
    if a.objects != b.objects {
        words.push(format!("the objects {}", a.objects.join(", ")));
    }
    if words.is_empty() {
        // Only the shard differs, which a row never shows.
        words.push(a.describe());
    }
    words
}

/// What a row's task is under its settings: "5 objects × 3 attempts" or "all 15 objects at once,
/// at most 25 attempts".
fn what(task: Task, settings: &Comparable) -> String {
    let objects = counted(settings.objects.len(), "object");
    match settings.max_attempts {
        Some(n) if task == Task::EmptyBin => {
            format!("all {objects} at once, at most {n} attempts")
        }
        _ if task == Task::Scenes => format!(
            "{}: {}; VPG's metrics",
            counted(settings.objects.len(), "scene file"),
            settings.objects.join(", ")
        ),
        _ => format!("{objects} × 3 attempts"),
    }
}

/// One policy's figures: success with its Wilson interval (and empty_bin's objects moved), its
/// seeds and attempts, linked to its kept report.
fn cell(entry: &Entry, task: Task, files: &mut Files) -> anyhow::Result<String> {
    let r = &entry.report.results;
    let s = &r.success;
    let link = files.copy(&entry.path, &entry.copy_name)?;
    let rate = format!("{}/{} = {:.1} %", s.successes, s.trials, 100.0 * s.rate);
    let headline = match (&r.moved, task) {
        (Some(moved), Task::EmptyBin) => {
            let of = r
                .runs
                .first()
                .and_then(|run| run.bin.as_ref())
                .map_or(0, |b| b.locations.len());
            let spread = if moved.count > 1 {
                format!(" ± {:.1}", moved.std)
            } else {
                String::new()
            };
            format!(
                "<b>{:.1}{spread} of {of} moved</b>, picks {rate}",
                moved.mean
            )
        }
        (_, Task::Scenes) => match r.cases.last() {
            Some(mean) => {
                let percent =
                    |v: Option<f64>| v.map_or("–".into(), |v| format!("{:.1} %", 100.0 * v));
                format!(
                    "<b>completion {}</b>, grasp success {}, action efficiency {}",
                    percent(Some(mean.completion)),
                    percent(mean.grasp_success),
                    percent(mean.action_efficiency)
                )
            }
            None => format!("<b>{rate}</b>"),
        },
        _ => format!("<b>{rate}</b>"),
    };
    let seeds = &entry.settings.seeds;
    let interrupted = if r.interrupted { ", interrupted" } else { "" };
    Ok(format!(
        "<td>{headline} <small><a href=\"{}\">report</a></small><br><small>95 % CI {:.1}–{:.1} % · {} {} · {}{interrupted}</small></td>",
        esc(&link),
        100.0 * s.wilson_low,
        100.0 * s.wilson_high,
        if seeds.len() == 1 { "seed" } else { "seeds" },
        esc(&seed_list(seeds)),
        counted(s.trials, "attempt")
    ))
}

/// The cell of a policy with no run yet: the command that makes one.
fn not_run(row: &Row, policy: PolicyKind, files: &Files) -> String {
    if row.task == Task::Scenes {
        return format!(
            "<td class=\"none\">not run: the model's eval command with <code>--policy {}</code></td>",
            policy.name()
        );
    }
    let flags = row
        .settings
        .filter(|s| !s.is_default())
        .map_or_else(String::new, Comparable::eval_flags);
    let command = files.command(&format!(
        "eval --task {} --policy {}{flags}",
        row.task.name(),
        policy.name()
    ));
    format!(
        "<td class=\"none\">not run: <code>{}</code></td>",
        esc(&command)
    )
}

/// The episode video (the model's empty_bin first, then any other recorded one) beside one
/// picture of the network's scores; the kept report whose video it is.
fn first_media(
    main: &[Entry],
    rounds: &[Round],
    files: &mut Files,
) -> anyhow::Result<(String, Option<PathBuf>)> {
    let mut order: Vec<&Entry> = Vec::new();
    for &task in [Task::EmptyBin, Task::Test, Task::Train].iter() {
        for group in groups(main.iter().filter(|e| e.task == task)) {
            order.extend(group);
        }
    }
    order.extend(rounds.iter().flat_map(|r| &r.entries));
    let filmed = order
        .iter()
        .find(|e| e.recorded_video().is_some_and(|v| e.locate(v).is_some()));
    let mut html = String::from("<div class=\"media\">\n");
    let top = match filmed {
        Some(entry) => {
            let _ = writeln!(
                html,
                "<figure class=\"episode\">{}<figcaption>The {} episode of the {} policy, {} {}: the arm (left) and the camera's view with each grasp (right).</figcaption></figure>",
                video(entry, files)?,
                esc(entry.task.name()),
                esc(entry.policy.name()),
                if entry.settings.seeds.len() == 1 { "seed" } else { "seeds" },
                esc(&seed_list(&entry.settings.seeds))
            );
            Some(entry.path.clone())
        }
        None => {
            html.push_str(&super::html::missing(
                "No episode video yet",
                &files.command(&format!(
                    "eval --task empty_bin --n-past-action 8 --record {}",
                    files.video_path("empty_bin.mp4")
                )),
            ));
            None
        }
    };
    // The filmed run's first picture when the model ran it, else the first model run's.
    let drawn = filmed
        .into_iter()
        .chain(order.iter())
        .filter(|e| e.policy == PolicyKind::Model)
        .find_map(|e| e.pictures().into_iter().next().map(|p| (*e, p)));
    if let Some((entry, picture)) = drawn {
        let key =
            " The network's scores as heat over the camera's image, from the picture's lowest \
                   to its highest score on a square-root scale (the colour bar): left, the best of \
                   the 8 angles, with the executed grasp as the open gripper (to scale); right, \
                   each angle, the chosen one framed.";
        if let Some(figure) = figure(entry, &picture, files, key)? {
            html.push_str(&figure);
        }
    }
    html.push_str("</div>\n");
    Ok((html, top))
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use crate::named::Named;
    use crate::policy::PolicyKind;
    use crate::present::eval_report::{summarise, Task};
    use crate::present::report_page::write_report_page;

    /// Writes a kept report of `policy` on `task` with `seeds` (and no attempts) under
    /// `home/reports`, as `eval` names the defaults' (the page reads the settings inside).
    fn keep(home: &Path, task: Task, policy: PolicyKind, seeds: &[u64], tag: &str) {
        let results = summarise(task, policy, seeds.to_vec(), &[], Vec::new(), 0.0, false);
        // Every setting eval writes: the page reads kept reports as strictly as merge does.
        let config = serde_json::json!({
            "global": {
                "data": home,
                "objects_dir": "bundled:objects",
                "split_path": "bundled:objects/split.json",
            },
            "task": task,
            "policy": policy,
            "seeds": seeds,
            "objects": ["YcbBanana"],
            "suppression": { "remember": 0 },
            "max_attempts": 25,
            "give_up_after": 0,
            "record": null,
        });
        let name = format!("eval_{}_{}{tag}.json", task.name(), policy.name());
        let path = home.join("reports").join(name);
        crate::present::envelope::write_versioned_report(&path, "eval", 2, 0, &config, &results)
            .unwrap();
    }

    #[test]
    fn the_table_comes_first_with_the_rounds_and_warns_of_other_settings() {
        let dir = tempfile::tempdir().unwrap();
        let data = dir.path().join("data");
        keep(&data, Task::Test, PolicyKind::Model, &[0], "");
        keep(&data, Task::Test, PolicyKind::Random, &[0], "");
        keep(&data, Task::Test, PolicyKind::Oracle, &[5], "_other");
        let round = data.join("improve/round_02");
        keep(&round, Task::EmptyBin, PolicyKind::Model, &[1, 2, 3], "");
        let out = dir.path().join("r.html");
        write_report_page(&data, &out).unwrap();
        let html = std::fs::read_to_string(&out).unwrap();
        let table = html
            .find("<table class=\"results\">")
            .expect("the results table");
        assert!(
            table < html.find("<details>").unwrap(),
            "the table comes first"
        );
        assert!(
            html.contains("<tr><th>improve round 2: empty_bin"),
            "{html}"
        );
        assert!(html.contains("⚠ oracle ran with seed 5, the model with seed 0: not comparable."));
        // The random run shares the model's settings: no warning for it.
        assert!(!html.contains("⚠ random"));
        // The round's report and DATA's share a name; each keeps its own copy.
        assert!(html.contains("r_files/reports/improve_round_02_eval_empty_bin_model.json"));
        let data = crate::named::shell_word(&data.display().to_string());
        assert!(
            html.contains(&format!(
                "<td class=\"none\" colspan=\"3\">not run yet: <code>graspmap --data {data} eval --task train</code>"
            )),
            "{html}"
        );
    }
}
