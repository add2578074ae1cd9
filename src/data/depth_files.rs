//! The depth image stored beside each label, `<Object>_<k>_depth.png` (16-bit millimetres), and
//! what `label --check` verifies about those files (docs/data.md).
//!
//! Depth files are sidecars of `<Object>_<k>_rgb.png`: same `<Object>_<k>` stem, written before
//! it, and optional as a set (a reference dataset has none), but once one exists every label needs
//! its own.

use std::collections::HashSet;
use std::path::PathBuf;

use super::input::read_depth_png;
use super::labels::{LabelStore, DEPTH_SUFFIX, LABELS_FILE};

/// Every problem with the dataset's depth files, one line each: none when it has no depth file
/// at all (the reference layout); otherwise a listed label without its depth file, a depth file
/// that is not a 128 × 128 16-bit PNG, and a depth file that no label lists.
pub(crate) fn check_depth_files(store: &LabelStore) -> Vec<String> {
    // A broken labels.json is reported by the main check; there is nothing to pair files with.
    let Ok(labels) = store.load() else {
        return Vec::new();
    };
    let listed: Vec<PathBuf> = labels
        .iter()
        .flat_map(|(object, list)| (1..=list.len()).map(move |k| store.depth_path(object, k)))
        .collect();
    let mut on_disk: Vec<PathBuf> = std::fs::read_dir(store.dir())
        .map(|entries| {
            entries
                .flatten()
                .map(|e| e.path())
                .filter(|p| p.to_string_lossy().ends_with(DEPTH_SUFFIX))
                .collect()
        })
        .unwrap_or_default();
    on_disk.sort();
    if on_disk.is_empty() {
        return Vec::new();
    }
    let mut problems = Vec::new();
    for path in &listed {
        if !path.exists() {
            problems.push(format!(
                "{}: missing depth image (once one label has a depth file, every label needs \
                 one; `graspmap label --backfill-depth` writes them)",
                path.display()
            ));
        } else if let Err(e) = read_depth_png(path) {
            problems.push(format!("{e:#}"));
        }
    }
    let listed: HashSet<PathBuf> = listed.into_iter().collect();
    for path in on_disk.iter().filter(|p| !listed.contains(*p)) {
        problems.push(format!(
            "{}: extra depth image not listed in {LABELS_FILE}",
            path.display()
        ));
    }
    problems
}
