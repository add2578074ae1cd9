//! The versioned JSON envelope every command's `--json` report shares (docs/data.md).

use std::io::Write;
use std::path::Path;

use serde::Serialize;

use crate::data::atomic::write_atomic;

/// The envelope of every `--json` report.
#[derive(Debug, Serialize)]
pub(crate) struct Report<'a, C: Serialize, R: Serialize> {
    /// `graspmap.<command>/<version>`.
    pub(crate) schema: String,
    /// Crate version.
    pub(crate) version: &'static str,
    /// Git commit the binary was built from.
    pub(crate) git_commit: &'static str,
    /// Seeds that drove the run.
    pub(crate) seed: u64,
    /// The fully resolved configuration.
    pub(crate) config: &'a C,
    /// The command's results.
    pub(crate) results: &'a R,
}

/// Writes a report to `target` (`-` = stdout) with schema `graspmap.<command>/1`.
pub(crate) fn write_report<C: Serialize, R: Serialize>(
    target: &Path,
    command: &str,
    seed: u64,
    config: &C,
    results: &R,
) -> anyhow::Result<()> {
    write_versioned_report(target, command, 1, seed, config, results)
}

/// Writes a report with schema `graspmap.<command>/<version>` (docs/data.md lists the versions).
pub(crate) fn write_versioned_report<C: Serialize, R: Serialize>(
    target: &Path,
    command: &str,
    version: u32,
    seed: u64,
    config: &C,
    results: &R,
) -> anyhow::Result<()> {
    let report = Report {
        schema: format!("graspmap.{command}/{version}"),
        version: env!("CARGO_PKG_VERSION"),
        git_commit: env!("GRASPMAP_GIT_COMMIT"),
        seed,
        config,
        results,
    };
    let mut text = serde_json::to_string_pretty(&report)?;
    text.push('\n');
    if target == Path::new("-") {
        std::io::stdout().write_all(text.as_bytes())?;
        Ok(())
    } else {
        write_atomic(target, text.as_bytes())
    }
}
