//! Helpers shared by the end-to-end test files: run the binary, check one-line user errors.

use std::process::{Command, Output};

/// Runs the built `graspmap` with `args`, without any inherited log filter.
pub fn graspmap(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_graspmap"))
        .args(args)
        .env_remove("GRASPMAP_LOG")
        .output()
        .expect("running graspmap")
}

/// The commit build.rs embeds in the binary (every JSON report's `git_commit`): what
/// `git rev-parse --short=12 HEAD` says in the repository, or `unknown` where git or the
/// repository is missing. build.rs reruns when HEAD moves, so this is the binary's commit as long
/// as nothing was committed between the build and the test (as in CI).
pub fn build_commit() -> String {
    Command::new("git")
        .args(["rev-parse", "--short=12", "HEAD"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .ok()
        .filter(|o| o.status.success())
        .and_then(|o| String::from_utf8(o.stdout).ok())
        .map(|s| s.trim().to_owned())
        .unwrap_or_else(|| "unknown".to_owned())
}

/// The report an `eval` kept under DATA/reports, as its "report kept in PATH" line names it.
pub fn kept_report(output: &Output) -> std::path::PathBuf {
    let stdout = String::from_utf8_lossy(&output.stdout);
    let line = stdout
        .lines()
        .find_map(|l| l.strip_prefix("report kept in "))
        .unwrap_or_else(|| panic!("no kept report named in: {stdout}"));
    std::path::PathBuf::from(line.split(" (").next().unwrap())
}

/// Asserts success, showing stderr when it fails.
pub fn assert_ok(output: &Output) {
    assert!(
        output.status.success(),
        "status {:?}, stderr: {}",
        output.status.code(),
        String::from_utf8_lossy(&output.stderr)
    );
}

/// Asserts a user error: exit status 2 and a single stderr line that mentions every `needles`.
pub fn assert_user_error(output: &Output, needles: &[&str]) {
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "stderr: {stderr}");
    assert!(!stderr.contains("panicked"), "panic: {stderr}");
    assert_eq!(
        stderr.trim_end().lines().count(),
        1,
        "not one line: {stderr}"
    );
    for needle in needles {
        assert!(stderr.contains(needle), "{needle:?} missing from: {stderr}");
    }
}

/// Polls `ready` every few milliseconds until it holds. Fails, naming `what` it waited for (and
/// `why`, what `ready` saw last), when `child` ends first or `limit` passes.
pub fn poll_until(
    child: &mut std::process::Child,
    what: &str,
    limit: std::time::Duration,
    mut ready: impl FnMut() -> Result<(), String>,
) {
    let started = std::time::Instant::now();
    while let Err(why) = ready() {
        let ended = child.try_wait().unwrap();
        assert!(ended.is_none(), "it ended ({ended:?}) before {what}: {why}");
        assert!(
            started.elapsed() < limit,
            "no {what} within {limit:?}: {why}"
        );
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
}

/// Sends `signal` to a child process, as a user's Ctrl-C or a supervisor's SIGTERM would.
pub fn send_signal(child: &std::process::Child, signal: i32) {
    // SAFETY: kill only sends a signal to the given PID.
    assert_eq!(unsafe { libc::kill(child.id() as i32, signal) }, 0);
}

/// Every file of a labels dir but the writer's lock (it holds a PID), by name, with its bytes.
pub fn snapshot(dir: &std::path::Path) -> Vec<(String, Vec<u8>)> {
    let mut files: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .filter(|e| e.file_name() != ".lock")
        .map(|e| {
            (
                e.file_name().to_string_lossy().into_owned(),
                std::fs::read(e.path()).unwrap(),
            )
        })
        .collect();
    files.sort();
    files
}

/// A command line split into words as a POSIX shell would: blanks separate, single quotes
/// quote (the page quotes nothing else).
pub fn shell_words(line: &str) -> Vec<String> {
    let mut words = Vec::new();
    let (mut word, mut quoted, mut started) = (String::new(), false, false);
    for c in line.chars() {
        match c {
            '\'' => (quoted, started) = (!quoted, true),
            ' ' if !quoted => {
                if started {
                    words.push(std::mem::take(&mut word));
                }
                started = false;
            }
            c => {
                word.push(c);
                started = true;
            }
        }
    }
    if started {
        words.push(word);
    }
    words
}
