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

/// One round's folder and the evaluations kept in it.
pub(crate) struct Round {
    /// 1, 2, … as `round_01`, `round_02`, … name them.
    pub(crate) number: u32,
    /// The evaluations of the round's model.
    pub(crate) entries: Vec<Entry>,
    /// Its folder, `round_RR/`.
    pub(crate) dir: PathBuf,
}

/// Every `round_RR/` under `DATA/improve`, in round order, with its kept evaluations.
pub(crate) fn read_rounds(data_dir: &Path) -> anyhow::Result<Vec<Round>> {
    let Ok(listing) = std::fs::read_dir(data_dir.join("improve")) else {
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
            let entries = read_kept(&dir, &format!("improve_round_{number:02}_"))?;
            Ok(Round {
                number,
                entries,
                dir,
            })
        })
        .collect()
}

/// The folded section: the rounds' figures and each round's evaluations in full. Empty when
/// there is no round.
pub(crate) fn improve_section(
    data_dir: &Path,
    rounds: &[Round],
    files: &mut Files,
) -> anyhow::Result<String> {
    if rounds.is_empty() {
        return Ok(String::new());
    }
    let mut html = rounds_table(&data_dir.join("improve/summary.json"));
    for round in rounds {
        let _ = writeln!(html, "<h3>Round {}</h3>", round.number);
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
    let rounds = std::fs::read_to_string(path)
        .ok()
        .and_then(|text| serde_json::from_str::<serde_json::Value>(&text).ok())
        .and_then(|v| v.as_array().cloned());
    let Some(rounds) = rounds else {
        return format!(
            "<p class=\"note\">{} is missing or unreadable: the rounds' collection figures are not shown.</p>\n",
            esc(&path.display().to_string())
        );
    };
    let mut html = String::from(
        "<table><tr><th>round</th><th>trials collected</th><th>of which succeeded</th><th>trials so far</th><th>best validation loss</th><th>model</th></tr>\n",
    );
    for round in &rounds {
        let number = |key: &str| round[key].as_f64().unwrap_or(f64::NAN);
        let _ = writeln!(
            html,
            "<tr><td class=\"num\">{}</td><td class=\"num\">{}</td><td class=\"num\">{:.1} %</td><td class=\"num\">{}</td><td class=\"num\">{:.5}</td><td><code>{}</code></td></tr>",
            number("round"),
            number("trials"),
            100.0 * number("collection_success_rate"),
            number("trials_so_far"),
            number("best_val_loss"),
            esc(round["model"].as_str().unwrap_or("–"))
        );
    }
    html.push_str("</table>\n");
    html
}
