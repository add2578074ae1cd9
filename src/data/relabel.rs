//! Deleting a label, the reference's way to relabel: the object's later images (and any sidecar
//! files of theirs) move down one number so k stays 1..n, in one step that a kill cannot tear.
//!
//! The new dataset is built beside the old one as hard links (no image is copied), with its
//! own labels.json and progress.json, and the two directories then trade places with one
//! `renameat2(RENAME_EXCHANGE)`. Until that call DIR/labels is the old dataset; after it, the
//! new one. The staging directory a kill leaves behind is removed by the next writer.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context};

use super::atomic::write_atomic;
use super::labels::{LabelStore, Labels, LABELS_FILE};
use super::lock::LOCK_FILE;
use super::progress::{Progress, PROGRESS_FILE};

/// For the crash tests, in a build with the `fault-injection` feature only:
/// `GRASPMAP_TEST_ABORT_DELETE=N` aborts the process at step N of a delete (1: staging made,
/// 2: files linked, 3: labels.json written, 4: progress.json written, 5: directories
/// exchanged), as a kill at that moment would.
fn abort_point(step: u32) {
    #[cfg(feature = "fault-injection")]
    if std::env::var("GRASPMAP_TEST_ABORT_DELETE").is_ok_and(|v| v.trim() == step.to_string()) {
        std::process::abort();
    }
    #[cfg(not(feature = "fault-injection"))]
    let _ = step;
}

/// What a file in the labels directory is to a delete of `object`'s label k.
#[derive(Debug, PartialEq)]
enum Fate {
    /// Kept under its name.
    Keep,
    /// The deleted label's image or sidecar.
    Drop,
    /// A later label's file, renamed to this.
    Renumber(String),
    /// Rewritten by the delete itself, or a temporary.
    Skip,
}

/// The file's fate: `<object>_<i>_<rest>` files of the object are label files.
fn fate(name: &str, object: &str, k: usize) -> Fate {
    if name == LABELS_FILE || name == PROGRESS_FILE || name.contains(".tmp-") {
        return Fate::Skip;
    }
    let Some(rest) = name.strip_prefix(object).and_then(|r| r.strip_prefix('_')) else {
        return Fate::Keep;
    };
    let Some((number, suffix)) = rest.split_once('_') else {
        return Fate::Keep;
    };
    match number.parse::<usize>() {
        Ok(i) if i == k => Fate::Drop,
        Ok(i) if i > k && !number.starts_with('0') => {
            Fate::Renumber(format!("{object}_{}_{suffix}", i - 1))
        }
        _ => Fate::Keep,
    }
}

impl LabelStore {
    /// Where a delete builds the next dataset: beside the labels directory, on its file system.
    fn staging_dir(&self) -> PathBuf {
        let name = self
            .dir()
            .file_name()
            .map_or_else(|| "labels".into(), |n| n.to_string_lossy().into_owned());
        self.dir().with_file_name(format!(".{name}.next"))
    }

    /// Removes the staging directory a killed delete left (either dataset in it is the one not
    /// chosen, so it is never needed).
    pub(crate) fn remove_stale_staging(&self) -> anyhow::Result<()> {
        let staging = self.staging_dir();
        if staging.exists() {
            std::fs::remove_dir_all(&staging)
                .with_context(|| format!("removing {}", staging.display()))?;
        }
        Ok(())
    }

    /// Deletes `object`'s label `k` (1-based) on disk and in `labels` and `progress`; the
    /// caller holds the store's writer lock.
    pub(crate) fn delete_label(
        &self,
        labels: &mut Labels,
        progress: Option<&mut Progress>,
        object: &str,
        k: usize,
    ) -> anyhow::Result<()> {
        let n = labels.of(object).len();
        if !(1..=n).contains(&k) {
            bail!(
                "{object} has {n} labels in {}; label {k} does not exist (k is 1..={n})",
                self.dir().display()
            );
        }
        let mut next_labels = labels.clone();
        next_labels.remove(object, k);
        let mut next_progress = progress.as_deref().cloned();
        if let Some(next) = &mut next_progress {
            next.remove_label(object, k);
        }

        self.remove_stale_staging()?;
        let staging = self.staging_dir();
        std::fs::create_dir(&staging).with_context(|| format!("creating {}", staging.display()))?;
        abort_point(1);
        self.link_survivors(&staging, object, k)?;
        abort_point(2);
        write_atomic(&staging.join(LABELS_FILE), next_labels.to_json().as_bytes())?;
        abort_point(3);
        if let Some(next) = &next_progress {
            let mut text = serde_json::to_vec_pretty(next)?;
            text.push(b'\n');
            write_atomic(&staging.join(PROGRESS_FILE), &text)?;
        }
        abort_point(4);
        sync_dir(&staging)?;
        exchange(&staging, self.dir())?;
        if let Some(parent) = self.dir().parent() {
            sync_dir(parent)?;
        }
        abort_point(5);
        std::fs::remove_dir_all(&staging)
            .with_context(|| format!("removing the old labels in {}", staging.display()))?;
        *labels = next_labels;
        if let (Some(progress), Some(next)) = (progress, next_progress) {
            *progress = next;
        }
        Ok(())
    }

    /// Hard-links every file that survives the delete into `staging`, under its new name. The
    /// lock file is linked too: the same inode, so the writer's lock holds across the exchange.
    fn link_survivors(&self, staging: &Path, object: &str, k: usize) -> anyhow::Result<()> {
        let entries = std::fs::read_dir(self.dir())
            .with_context(|| format!("reading {}", self.dir().display()))?;
        for entry in entries {
            let entry = entry.with_context(|| format!("reading {}", self.dir().display()))?;
            let name = entry.file_name().to_string_lossy().into_owned();
            let target = match fate(&name, object, k) {
                Fate::Keep => name.clone(),
                Fate::Renumber(renamed) => renamed,
                Fate::Drop | Fate::Skip => continue,
            };
            if name != LOCK_FILE && !entry.file_type().is_ok_and(|t| t.is_file()) {
                continue;
            }
            let to = staging.join(&target);
            std::fs::hard_link(entry.path(), &to)
                .or_else(|_| std::fs::copy(entry.path(), &to).map(|_| ()))
                .with_context(|| {
                    format!("linking {} to {}", entry.path().display(), to.display())
                })?;
        }
        Ok(())
    }
}

/// Makes a directory's entries durable.
fn sync_dir(dir: &Path) -> anyhow::Result<()> {
    std::fs::File::open(dir)
        .and_then(|d| d.sync_all())
        .with_context(|| format!("syncing {}", dir.display()))
}

/// Swaps two directories atomically.
#[cfg(target_os = "linux")]
fn exchange(a: &Path, b: &Path) -> anyhow::Result<()> {
    use std::os::unix::ffi::OsStrExt;
    let c = |p: &Path| std::ffi::CString::new(p.as_os_str().as_bytes());
    let (ca, cb) = (c(a)?, c(b)?);
    // SAFETY: both paths are NUL-terminated strings that live across the call.
    let status = unsafe {
        libc::renameat2(
            libc::AT_FDCWD,
            ca.as_ptr(),
            libc::AT_FDCWD,
            cb.as_ptr(),
            libc::RENAME_EXCHANGE,
        )
    };
    if status != 0 {
        return Err(std::io::Error::last_os_error())
            .with_context(|| format!("exchanging {} with {}", a.display(), b.display()));
    }
    Ok(())
}

/// Elsewhere there is no atomic exchange: two renames, with a short window in which the
/// labels directory is missing (a rerun finds the old dataset at the staging path's sibling).
#[cfg(not(target_os = "linux"))]
fn exchange(a: &Path, b: &Path) -> anyhow::Result<()> {
    let old = b.with_extension("old");
    std::fs::rename(b, &old).with_context(|| format!("moving {}", b.display()))?;
    std::fs::rename(a, b).with_context(|| format!("moving {}", a.display()))?;
    std::fs::rename(&old, a).with_context(|| format!("moving {}", old.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn files_of_later_labels_move_down_and_others_stay() {
        let f = |name| fate(name, "YcbHammer", 2);
        assert_eq!(f("YcbHammer_2_rgb.png"), Fate::Drop);
        assert_eq!(f("YcbHammer_2_depth.png"), Fate::Drop);
        assert_eq!(
            f("YcbHammer_3_rgb.png"),
            Fate::Renumber("YcbHammer_2_rgb.png".into())
        );
        assert_eq!(
            f("YcbHammer_12_depth.png"),
            Fate::Renumber("YcbHammer_11_depth.png".into())
        );
        assert_eq!(f("YcbHammer_1_rgb.png"), Fate::Keep);
        assert_eq!(f("YcbHammerX_3_rgb.png"), Fate::Keep);
        assert_eq!(f("YcbBanana_3_rgb.png"), Fate::Keep);
        assert_eq!(f("YcbHammer_03_rgb.png"), Fate::Keep);
        assert_eq!(f(LABELS_FILE), Fate::Skip);
        assert_eq!(f(PROGRESS_FILE), Fate::Skip);
        assert_eq!(f(".labels.json.tmp-12"), Fate::Skip);
        assert_eq!(f(LOCK_FILE), Fate::Keep);
    }
}
