//! `improve`'s `summary.json`: one line per round, written by `improve` into its `--out` folder
//! (all rounds) and each `round_RR/` (that round), read back by `report` in the same types.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::data::atomic::write_atomic;

/// The file's name, in the rounds' folder and in each round's.
pub(crate) const FILE: &str = "summary.json";

/// One round's line of `summary.json`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RoundSummary {
    pub(crate) round: u32,
    pub(crate) collected_with: PathBuf,
    pub(crate) trials: usize,
    pub(crate) successes: usize,
    pub(crate) collection_success_rate: f64,
    pub(crate) trials_so_far: usize,
    pub(crate) best_val_loss: f64,
    pub(crate) model: PathBuf,
    pub(crate) collect_seconds: f64,
    pub(crate) train_seconds: f64,
    /// Absent without `--eval-seeds`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) eval: Option<EvalSummary>,
}

/// The figures of a round's empty_bin evaluation.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct EvalSummary {
    pub(crate) seeds: Vec<u64>,
    pub(crate) moved_mean: f64,
    pub(crate) pick_success_rate: f64,
    pub(crate) report: PathBuf,
    pub(crate) seconds: f64,
}

/// Writes a summary (one round's, or the list of all) atomically, pretty-printed.
pub(crate) fn write(path: &Path, value: &impl Serialize) -> anyhow::Result<()> {
    let text = serde_json::to_string_pretty(value)? + "\n";
    write_atomic(path, text.as_bytes())
}

/// Reads the rounds' `summary.json`: every field typed, none filled in, an unknown one refused;
/// an error names the file.
pub(crate) fn read_all(path: &Path) -> anyhow::Result<Vec<RoundSummary>> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| anyhow::anyhow!("{}: {}", path.display(), crate::data::output::reason(&e)))?;
    serde_json::from_str(&text).map_err(|e| {
        anyhow::anyhow!(
            "{} is not improve's summary of its rounds ({e}); rerun the same improve command",
            path.display()
        )
    })
}

/// The list of the folders that `improve --out` put rounds in, under the data directory's
/// `reports/`, so that `report` finds every run's rounds, not only those under `DATA/improve`.
const RUNS_FILE: &str = "improve_runs.json";

/// Every folder of improve rounds for the data directory `data`: `DATA/improve` first, then
/// those that `improve --out` recorded, in the order they were first run; the missing left out.
pub(crate) fn run_folders(data: &Path) -> anyhow::Result<Vec<PathBuf>> {
    let mut folders = vec![data.join("improve")];
    let list = data.join("reports").join(RUNS_FILE);
    if list.is_file() {
        let text = std::fs::read_to_string(&list).map_err(|e| {
            anyhow::anyhow!("{}: {}", list.display(), crate::data::output::reason(&e))
        })?;
        let recorded: Vec<PathBuf> = serde_json::from_str(&text).map_err(|e| {
            anyhow::anyhow!(
                "{} is not a list of improve folders ({e}); delete it, and rerun improve to record its --out again",
                list.display()
            )
        })?;
        folders.extend(recorded.into_iter().filter(|f| f.is_dir()));
    }
    Ok(folders)
}

/// Records `out` as a folder of improve rounds of the data directory `data` (nothing to do for
/// `DATA/improve`, where `report` always looks, or a folder already listed).
pub(crate) fn record_run(data: &Path, out: &Path) -> anyhow::Result<()> {
    let out = std::path::absolute(out)?;
    let own = std::path::absolute(data.join("improve"))?;
    let list = data.join("reports").join(RUNS_FILE);
    let mut recorded: Vec<PathBuf> = match std::fs::read_to_string(&list) {
        Ok(text) => serde_json::from_str(&text).unwrap_or_default(),
        Err(_) => Vec::new(),
    };
    if out == own || recorded.contains(&out) {
        return Ok(());
    }
    recorded.push(out);
    write(&list, &recorded)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_summary_reads_back_as_written_and_a_renamed_field_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join(FILE);
        let round = RoundSummary {
            round: 1,
            collected_with: "a.safetensors".into(),
            trials: 10,
            successes: 4,
            collection_success_rate: 0.4,
            trials_so_far: 10,
            best_val_loss: 0.25,
            model: "b.safetensors".into(),
            collect_seconds: 1.0,
            train_seconds: 2.0,
            eval: None,
        };
        write(&path, &vec![round.clone()]).unwrap();
        let read = read_all(&path).unwrap();
        assert_eq!(read.len(), 1);
        assert_eq!(read[0].best_val_loss, 0.25);
        assert_eq!(read[0].model, round.model);
        let renamed = std::fs::read_to_string(&path)
            .unwrap()
            .replace("best_val_loss", "best_loss");
        std::fs::write(&path, renamed).unwrap();
        let err = read_all(&path).unwrap_err().to_string();
        assert!(err.contains(FILE) && err.contains("best_loss"), "{err}");
    }
}
