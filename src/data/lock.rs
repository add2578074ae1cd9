//! One writer per store: an advisory lock on a file inside the directory that a command
//! writes (DIR/labels for `label`, DIR/affordance for `train`).
//!
//! The operating system releases the lock when its process ends, however it ends, so a lock
//! left by a process killed with SIGKILL never blocks the next run. The holder writes its PID
//! into the lock file so that a second writer can say who holds it.

use std::fs::{File, OpenOptions, TryLockError};
use std::io::{Read, Seek, Write};
use std::path::{Path, PathBuf};

/// The lock file's name inside a store.
pub const LOCK_FILE: &str = ".lock";

/// Why a store could not be locked.
#[derive(Debug, thiserror::Error)]
pub enum LockError {
    /// Another process writes the store.
    #[error(
        "{path} is held by {}: another graspmap {command} is writing {dir}; wait for it to \
         finish or stop it",
        match pid { Some(pid) => format!("process {pid}"), None => "another process".to_owned() },
        dir = path.parent().unwrap_or(Path::new(".")).display(),
        path = path.display()
    )]
    Held {
        /// The lock file.
        path: PathBuf,
        /// The holder's PID, as it wrote it.
        pid: Option<u32>,
        /// The command that takes this lock.
        command: &'static str,
    },
    /// The lock file cannot be opened or locked.
    #[error(
        "cannot write {dir} ({reason}); make it writable, or choose another --data",
        dir = path.parent().unwrap_or(Path::new(".")).display()
    )]
    Io {
        /// The lock file.
        path: PathBuf,
        /// What the system said, without its error code.
        reason: String,
    },
}

/// An exclusive hold on a store, released when dropped (or when the process dies).
#[derive(Debug)]
pub struct StoreLock {
    _file: File,
}

impl StoreLock {
    /// Takes the store's lock at once, or says who holds it; `command` names the writer.
    pub fn acquire(dir: &Path, command: &'static str) -> Result<Self, LockError> {
        let path = dir.join(LOCK_FILE);
        let io = |e: std::io::Error| LockError::Io {
            path: path.clone(),
            reason: crate::data::output::reason(&e),
        };
        std::fs::create_dir_all(dir).map_err(io)?;
        let mut file = OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(&path)
            .map_err(io)?;
        match file.try_lock() {
            Ok(()) => {}
            Err(TryLockError::WouldBlock) => {
                let mut text = String::new();
                let _ = file.read_to_string(&mut text);
                return Err(LockError::Held {
                    path,
                    pid: text.trim().parse().ok(),
                    command,
                });
            }
            Err(TryLockError::Error(e)) => return Err(io(e)),
        }
        file.set_len(0).map_err(io)?;
        file.rewind().map_err(io)?;
        writeln!(file, "{}", std::process::id()).map_err(io)?;
        Ok(Self { _file: file })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_holder_is_refused_with_the_first_ones_pid_until_it_lets_go() {
        let dir = tempfile::tempdir().unwrap();
        let first = StoreLock::acquire(dir.path(), "label").unwrap();
        let err = StoreLock::acquire(dir.path(), "label").unwrap_err();
        let text = err.to_string();
        assert!(
            text.contains(&format!("process {}", std::process::id())),
            "{text}"
        );
        assert!(text.contains(".lock"), "{text}");
        drop(first);
        StoreLock::acquire(dir.path(), "label").unwrap();
    }
}
