//! Outputs checked before the work starts: every command asks here, before its first scene,
//! epoch or round, whether each file and folder it will write can be written, so that a
//! read-only data directory or a mistyped `--json` path fails in a second with one line that
//! names the path, says why and gives the fix, not after an hour of simulation.
//!
//! The check creates what a command would create anyway (the folders under the data directory)
//! and probes each folder with a file that it removes at once.

use std::io::ErrorKind;
use std::path::{Path, PathBuf};

/// Why an output cannot be written.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// The path names a folder where a file is wanted.
    #[error("{what} {path} is a directory; give the path of a file (inside it, or elsewhere)")]
    IsDirectory { what: String, path: PathBuf },
    /// The folder that would hold the file does not exist.
    #[error("{what} {path}: the folder {parent} does not exist; create it first, or choose another path")]
    MissingParent {
        what: String,
        path: PathBuf,
        parent: PathBuf,
    },
    /// Something on the way is a file, not a folder.
    #[error("{what} {path}: {blocker} is a file, not a folder; choose another path")]
    NotAFolder {
        what: String,
        path: PathBuf,
        blocker: PathBuf,
    },
    /// The folder exists but cannot be written (read-only, no permission, full disk...).
    #[error("{what} {path}: cannot write in {folder} ({reason}); {fix}")]
    NotWritable {
        what: String,
        path: PathBuf,
        folder: PathBuf,
        reason: String,
        fix: &'static str,
    },
}

/// The fix offered for an unwritable folder.
const WRITABLE_FIX: &str =
    "make it writable (check its permissions and that the disk is not read-only or full), or choose another path";

/// The folder a file path lives in (`.` for a bare file name).
fn parent_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// Checks that `path` can be written as a file, the way the atomic writer writes it (a
/// temporary file beside it, then a rename); `what` names it in errors, e.g. `--json`. `-`
/// (stdout) always passes. The folder must exist: a missing one is more often a typo than a
/// wish.
pub(crate) fn check_output_file(path: &Path, what: &str) -> Result<(), OutputError> {
    if path == Path::new("-") {
        return Ok(());
    }
    if path.is_dir() {
        return Err(OutputError::IsDirectory {
            what: what.to_owned(),
            path: path.to_path_buf(),
        });
    }
    let parent = parent_of(path);
    if !parent.exists() {
        return Err(OutputError::MissingParent {
            what: what.to_owned(),
            path: path.to_path_buf(),
            parent,
        });
    }
    probe(&parent, path, what)
}

/// [`check_output_file`] for a path that may lie under the data directory `data`, where the
/// command creates the folders it needs (a default output, say); elsewhere the folder must exist.
pub(crate) fn check_output_file_in(
    path: &Path,
    what: &str,
    data: &Path,
) -> Result<(), OutputError> {
    let parent = parent_of(path);
    if parent.starts_with(data) && !parent.exists() {
        check_output_dir(&parent, what)?;
    }
    check_output_file(path, what)
}

/// Checks that the folder `dir` exists or can be created, and can be written; `what` names it.
pub(crate) fn check_output_dir(dir: &Path, what: &str) -> Result<(), OutputError> {
    if let Some(blocker) = dir.ancestors().find(|a| a.is_file()) {
        return Err(OutputError::NotAFolder {
            what: what.to_owned(),
            path: dir.to_path_buf(),
            blocker: blocker.to_path_buf(),
        });
    }
    if let Err(e) = std::fs::create_dir_all(dir) {
        // Name the deepest folder that exists: that is where the creation was refused.
        let folder = dir
            .ancestors()
            .find(|a| a.is_dir())
            .unwrap_or(Path::new("."))
            .to_path_buf();
        return Err(OutputError::NotWritable {
            what: what.to_owned(),
            path: dir.to_path_buf(),
            folder,
            reason: reason(&e),
            fix: WRITABLE_FIX,
        });
    }
    probe(dir, dir, what)
}

/// Creates and removes a file in `folder`.
fn probe(folder: &Path, path: &Path, what: &str) -> Result<(), OutputError> {
    let probe = folder.join(format!(".graspmap-probe-{}", std::process::id()));
    let created = std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe);
    match created {
        Ok(_) => {
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        Err(e) if e.kind() == ErrorKind::AlreadyExists => Ok(()),
        Err(e) => Err(OutputError::NotWritable {
            what: what.to_owned(),
            path: path.to_path_buf(),
            folder: folder.to_path_buf(),
            reason: reason(&e),
            fix: WRITABLE_FIX,
        }),
    }
}

/// The system's words for an error, without the `(os error N)` code.
pub(crate) fn reason(e: &std::io::Error) -> String {
    let text = e.to_string();
    match text.find(" (os error") {
        Some(i) => text[..i].to_lowercase(),
        None => text.to_lowercase(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_folder_a_missing_parent_and_a_file_in_the_way_are_each_named() {
        let dir = tempfile::tempdir().unwrap();
        let err = check_output_file(dir.path(), "--json").unwrap_err();
        assert!(err.to_string().contains("is a directory"), "{err}");
        let missing = dir.path().join("nope").join("r.json");
        let err = check_output_file(&missing, "--json").unwrap_err();
        assert!(err.to_string().contains("does not exist"), "{err}");
        let file = dir.path().join("file");
        std::fs::write(&file, b"x").unwrap();
        let err = check_output_dir(&file.join("reports"), "the reports folder").unwrap_err();
        assert!(err.to_string().contains("is a file, not a folder"), "{err}");
        check_output_file(&dir.path().join("r.json"), "--json").unwrap();
        check_output_dir(&dir.path().join("a").join("b"), "the data folder").unwrap();
        assert!(dir.path().join("a").join("b").is_dir());
        check_output_file(Path::new("-"), "--json").unwrap();
        // The probe leaves nothing behind.
        let left: Vec<_> = std::fs::read_dir(dir.path().join("a").join("b"))
            .unwrap()
            .collect();
        assert!(left.is_empty());
    }

    #[test]
    fn the_reason_is_said_once_without_the_error_code() {
        let e = std::io::Error::from_raw_os_error(libc::EACCES);
        assert_eq!(reason(&e), "permission denied");
    }
}
