//! Commands: each orchestrates the core, the objects and the simulator, and owns all printing.

mod arranged;
mod attempt;
pub(crate) mod bench;
pub(crate) mod collect;
pub(crate) mod eval;
pub(crate) mod grasp;
pub(crate) mod improve;
pub(crate) mod label;
pub(crate) mod merge;
pub(crate) mod predict;
pub(crate) mod report;
pub(crate) mod scene;
pub(crate) mod train;
pub(crate) mod workers;

use std::path::{Path, PathBuf};

use crate::assets::objects::{ObjectLibrary, Split, SplitFile};

/// Who runs a stage (`collect`, `train`, `eval`): its own command, or `improve`, whose flags
/// differ (no `--force`, `--resume` or `--out-dir`); the advice of a stage's errors names only
/// flags that the command the user typed has.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) enum RunBy {
    /// The stage's own command.
    #[default]
    Own,
    /// A round of `graspmap improve`.
    Improve,
}

/// Settings shared by every command, resolved once by the CLI from the global flags.
#[derive(Debug, Clone)]
pub(crate) struct Context {
    /// Data directory.
    pub(crate) data: PathBuf,
    /// Object models.
    pub(crate) objects: ObjectLibrary,
    /// The train/test split.
    pub(crate) split: SplitFile,
    /// Worker threads.
    pub(crate) threads: u16,
    /// Where to write JSON results.
    pub(crate) json: Option<PathBuf>,
    /// No progress output.
    pub(crate) quiet: bool,
    /// The subcommand as typed (`eval`, …): its `--json` report's schema is
    /// `graspmap.<command>/N`.
    pub(crate) command: &'static str,
}

/// How the context appears as `"global"` in every report: the same keys as ever, with the
/// bundled models named `bundled:…` since they have no path on disk.
impl serde::Serialize for Context {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        let mut global = serializer.serialize_struct("Context", 7)?;
        global.serialize_field("data", &self.data)?;
        global.serialize_field(
            "assets",
            &format!("{}assets", crate::assets::BUNDLED_PREFIX),
        )?;
        global.serialize_field("objects_dir", &self.objects.location())?;
        global.serialize_field("split_path", &self.split.location())?;
        global.serialize_field("threads", &self.threads)?;
        global.serialize_field("json", &self.json)?;
        global.serialize_field("quiet", &self.quiet)?;
        global.end()
    }
}

impl Context {
    /// The split, read on demand.
    pub(crate) fn split(&self) -> anyhow::Result<Split> {
        let split = self.split.read()?;
        split.check_objects(&self.split.location(), &self.objects)?;
        Ok(split)
    }

    /// Prints a human-readable result line: to stdout, unless the JSON report goes there.
    /// A reader that went away (`graspmap eval ... | head -1`) is no error: the command goes on
    /// and still writes its files, it only stops printing.
    pub(crate) fn say(&self, line: &str) {
        use std::io::Write;
        let _ = if self.json.as_deref() == Some(Path::new("-")) {
            writeln!(std::io::stderr().lock(), "{line}")
        } else {
            writeln!(std::io::stdout().lock(), "{line}")
        };
    }

    /// A line about the run rather than its results (resuming, nothing to do, a scene's
    /// progress): to stderr, so that stdout carries results only, and not under `--quiet`.
    pub(crate) fn note(&self, line: &str) {
        if !self.quiet {
            eprintln!("{line}");
        }
    }

    /// What a stopped run kept and how to continue it: to stderr, with the error it ends with,
    /// under `--quiet` too.
    pub(crate) fn stopped(&self, line: &str) {
        eprintln!("{line}");
    }

    /// A progress bar with ETA over `len` `unit`s, `done` already: drawn on a terminal,
    /// hidden under `--quiet`, in CI and when stderr is redirected. The ETA is the pace of this
    /// run's units (units resumed from an earlier run count as none), and reads `…` until the
    /// first of them is done.
    pub(crate) fn progress_bar(&self, unit: &str, len: u64, done: u64) -> indicatif::ProgressBar {
        if !self.shows_progress() {
            return indicatif::ProgressBar::hidden();
        }
        let bar = indicatif::ProgressBar::new(len);
        let estimate = move |state: &indicatif::ProgressState, w: &mut dyn std::fmt::Write| {
            let _ = match state.pos() > done {
                true => write!(w, "{:#}", indicatif::HumanDuration(state.eta())),
                false => write!(w, "…"),
            };
        };
        bar.set_style(
            indicatif::ProgressStyle::with_template(&format!(
                "{{bar:30}} {{pos}}/{{len}} {unit}  {{msg}}  [{{elapsed_precise}}, ETA {{estimate}}]"
            ))
            .expect("the template is valid")
            .with_key("estimate", estimate),
        );
        bar.set_position(done);
        bar.reset_eta();
        bar
    }

    /// Whether progress is drawn: on a terminal, without `--quiet`.
    pub(crate) fn shows_progress(&self) -> bool {
        use std::io::IsTerminal;
        !self.quiet && std::io::stderr().is_terminal()
    }
}
