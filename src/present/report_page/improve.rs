//! The `improve` rounds under DATA/improve: each `round_RR/` that `graspmap improve` wrote, the
//! evaluations it kept there (`improve --eval-seeds`: the round's model on empty_bin, in
//! `round_RR/reports/`), and the rounds' own figures from `summary.json`.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::evals::details;
use super::files::Files;
use super::html::esc;
use super::kept::{read_kept, Entry};
use crate::named::shell_word;
use crate::present::improve_summary;

/// One round's folder and the evaluations kept in it.
pub(crate) struct Round {
    /// How the page names the round: "improve round 2", or with the folder of an `improve
    /// --out` run, "improve runs/a round 2".
    pub(crate) name: String,
    /// The folder of its run, which holds the rounds' `summary.json`.
    pub(crate) run: PathBuf,
    /// The evaluations of the round's model.
    pub(crate) entries: Vec<Entry>,
    /// Its folder, `round_RR/`.
    pub(crate) dir: PathBuf,
}

/// Every `round_RR/` of every improve run of the data directory (`DATA/improve`, then each
/// `--out` that improve recorded), in round order, with its kept evaluations.
pub(crate) fn read_rounds(data_dir: &Path) -> anyhow::Result<Vec<Round>> {
    let mut rounds = Vec::new();
    for (i, run) in improve_summary::run_folders(data_dir)?
        .into_iter()
        .enumerate()
    {
        let (name, prefix) = match i {
            0 => ("improve".to_owned(), "improve_".to_owned()),
            i => (format!("improve {}", run.display()), format!("improve{i}_")),
        };
        rounds.extend(read_run(&run, &name, &prefix)?);
    }
    Ok(rounds)
}

/// The rounds of one improve run in `run`.
fn read_run(run: &Path, name: &str, prefix: &str) -> anyhow::Result<Vec<Round>> {
    let Ok(listing) = std::fs::read_dir(run) else {
        return Ok(Vec::new());
    };
    let mut found: Vec<(u32, PathBuf)> = listing
        .filter_map(Result::ok)
        .filter_map(|e| {
            let name = e.file_name().to_str()?.to_owned();
            let number = name.strip_prefix("round_")?.parse().ok()?;
            e.path().is_dir().then(|| (number, e.path()))
        })
        .collect();
    found.sort();
    found
        .into_iter()
        .map(|(number, dir)| {
            let entries = read_kept(&dir, &format!("{prefix}round_{number:02}_"))?;
            Ok(Round {
                name: format!("{name} round {number}"),
                run: run.to_path_buf(),
                entries,
                dir,
            })
        })
        .collect()
}

/// The folded section: the rounds' figures and each round's evaluations in full. Empty when
/// there is no round.
pub(crate) fn improve_section(rounds: &[Round], files: &mut Files) -> anyhow::Result<String> {
    let mut html = String::new();
    for (i, round) in rounds.iter().enumerate() {
        if i == 0 || rounds[i - 1].run != round.run {
            let _ = writeln!(
                html,
                "<h3>Rounds in {}</h3>",
                esc(&round.run.display().to_string())
            );
            html.push_str(&rounds_table(&round.run.join(improve_summary::FILE)));
        }
        let _ = writeln!(html, "<h3>{}</h3>", esc(&round.name));
        if round.entries.is_empty() {
            // As improve --eval-seeds would have: the report kept in the round's folder.
            let model = round.dir.join("model").join("best.safetensors");
            let command = super::html::command(
                &round.dir,
                &format!(
                    "eval --task empty_bin --n-past-action 8 --checkpoint {}",
                    shell_word(&model.display().to_string())
                ),
            );
            let _ = writeln!(
                html,
                "<p class=\"note\">No evaluation of this round's model: <code>{}</code> makes one.</p>",
                esc(&command)
            );
        }
        for entry in &round.entries {
            html.push_str(&details(entry, files, false)?);
        }
    }
    Ok(html)
}

/// The table of `improve`'s summary.json: per round, the trials collected and the retrained
/// model's best validation loss. A summary that is missing or unreadable is said so, not an
/// error: the rounds' evaluations stand without it.
fn rounds_table(path: &Path) -> String {
    let rounds = match improve_summary::read_all(path) {
        Ok(rounds) => rounds,
        Err(e) => {
            return format!(
                "<p class=\"note\">The rounds' collection figures are not shown: {}.</p>\n",
                esc(&format!("{e:#}"))
            )
        }
    };
    let mut html = String::from(
        "<table><tr><th>round</th><th>trials collected</th><th>of which succeeded</th><th>trials so far</th><th>best validation loss</th><th>model</th></tr>\n",
    );
    for round in &rounds {
        let _ = writeln!(
            html,
            "<tr><td class=\"num\">{}</td><td class=\"num\">{}</td><td class=\"num\">{:.1} %</td><td class=\"num\">{}</td><td class=\"num\">{:.5}</td><td><code>{}</code></td></tr>",
            round.round,
            round.trials,
            100.0 * round.collection_success_rate,
            round.trials_so_far,
            round.best_val_loss,
            esc(&round.model.display().to_string())
        );
    }
    html.push_str("</table>\n");
    html
}
