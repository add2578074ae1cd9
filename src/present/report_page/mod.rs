//! The run report: one self-contained HTML page for a whole run, written beside a folder of the
//! files it shows and linked relatively, so that the pair opens offline and travels as a zip.
//! The first screen holds the results (summary.rs: every task's model and baselines, the
//! `improve` rounds, the episode video and a picture of the network's scores); the labels, the
//! training, every kept evaluation and the rounds in full follow, folded.
//!
//! [`write_report_page`] is the one entry point; `graspmap report` and its `--serve` call it.

mod evals;
mod files;
mod html;
mod improve;
mod kept;
mod run_parts;
mod summary;

use std::path::{Path, PathBuf};

pub(crate) use files::files_dir;
use files::Files;
use html::esc;

/// The page's frame and style, embedded in the binary (no CDN, no script).
const TEMPLATE: &str = include_str!("page.html");

/// Writes the report of the run under `data_dir` to `out_html`, and the files it shows to
/// `<stem>_files/` beside it (only relative links between them). Returns the page's path first,
/// then every file written. Parts of the run that do not exist yet appear as a line naming the
/// command that makes them; a corrupt labels file or eval report is an error naming it.
pub(crate) fn write_report_page(data_dir: &Path, out_html: &Path) -> anyhow::Result<Vec<PathBuf>> {
    if out_html.is_dir() {
        anyhow::bail!(
            "{} is a directory; give the page's file name, e.g. {}",
            out_html.display(),
            out_html.join("report.html").display()
        );
    }
    let mut files = Files::new(out_html, data_dir);
    let main = kept::read_kept(data_dir, "")?;
    let rounds = improve::read_rounds(data_dir)?;
    let (mut body, top) = summary::summary_section(&main, &rounds, &mut files)?;
    let labels = run_parts::labels_section(data_dir, &mut files)?;
    body.push_str(&fold("Labels", &labels));
    let training = run_parts::training_section(data_dir, &mut files)?;
    body.push_str(&fold("Training", &training));
    let evals = evals::evals_section(&main, &mut files, top.as_deref())?;
    body.push_str(&fold(
        "Evaluations: every kept report, its tables, pictures and video",
        &evals,
    ));
    let improve = improve::improve_section(&rounds, &mut files)?;
    if !improve.is_empty() {
        body.push_str(&fold("Learning from trials: the improve rounds", &improve));
    }
    let meta = format!(
        "Data directory <code>{}</code>; graspmap {} (commit {}).",
        esc(&data_dir.display().to_string()),
        env!("CARGO_PKG_VERSION"),
        env!("GRASPMAP_GIT_COMMIT")
    );
    let html = TEMPLATE
        .replace("{{title}}", "graspmap run report")
        .replace("{{meta}}", &meta)
        .replace("{{body}}", &body);
    files.finish(&html)
}

/// A part of the page folded under its title: one click opens it.
fn fold(title: &str, html: &str) -> String {
    format!(
        "<details><summary><h2>{}</h2></summary>\n{html}</details>\n",
        esc(title)
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_empty_data_directory_gives_a_page_of_missing_parts() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("r.html");
        let data = dir.path().join("nothing");
        let written = write_report_page(&data, &out).unwrap();
        assert_eq!(written, std::slice::from_ref(&out));
        let html = std::fs::read_to_string(&out).unwrap();
        // Each names the data directory, so that it runs as printed from anywhere.
        for command in ["label", "train --epochs 30", "eval --task train"] {
            let command = html::command(&data, command);
            assert!(html.contains(&command), "{command} missing from {html}");
        }
        assert!(!html.contains("{{"), "a placeholder is left");
    }
}
