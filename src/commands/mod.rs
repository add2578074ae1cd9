//! Commands: each orchestrates the core, the objects and the simulator, and owns all printing.

pub mod bench;
pub mod eval;
pub mod grasp;
pub mod label;
pub mod predict;
pub mod scene;
pub mod train;

use std::path::{Path, PathBuf};

use crate::cli::GlobalArgs;
use crate::objects::{ObjectLibrary, Split};

/// The bundled assets directory (robot and object models).
pub fn bundled_assets() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("assets")
}

/// Settings shared by every command, resolved once from the global flags.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Context {
    /// Data directory.
    pub data: PathBuf,
    /// Robot and gripper assets.
    pub assets: PathBuf,
    /// Object models directory.
    pub objects_dir: PathBuf,
    /// Split file.
    pub split_path: PathBuf,
    /// Worker threads.
    pub threads: u16,
    /// Where to write JSON results.
    pub json: Option<PathBuf>,
    /// No progress output.
    pub quiet: bool,
}

impl Context {
    /// Resolves defaults and checks the directories exist.
    pub fn from_args(args: &GlobalArgs) -> anyhow::Result<Self> {
        let assets = bundled_assets();
        let objects_dir = args
            .objects_dir
            .clone()
            .unwrap_or_else(|| assets.join("objects"));
        if !objects_dir.is_dir() {
            anyhow::bail!(
                "--objects-dir {} is not a directory (it should hold <Name>/model.urdf)",
                objects_dir.display()
            );
        }
        let split_path = args
            .split
            .clone()
            .unwrap_or_else(|| objects_dir.join("split.json"));
        let threads = args.threads.unwrap_or_else(|| {
            std::thread::available_parallelism()
                .map_or(1, |n| n.get().min(u16::MAX as usize) as u16)
        });
        Ok(Self {
            data: args.data.clone(),
            assets,
            objects_dir,
            split_path,
            threads,
            json: args.json.clone(),
            quiet: args.quiet,
        })
    }

    /// The object library.
    pub fn library(&self) -> ObjectLibrary {
        ObjectLibrary::new(&self.objects_dir)
    }

    /// The split, read on demand.
    pub fn split(&self) -> anyhow::Result<Split> {
        Ok(Split::read(&self.split_path)?)
    }

    /// Prints a human-readable result line: to stdout, unless the JSON report goes there.
    pub fn say(&self, line: &str) {
        if self.json.as_deref() == Some(Path::new("-")) {
            eprintln!("{line}");
        } else {
            println!("{line}");
        }
    }

    /// A progress bar with ETA over `len` `unit`s, `done` already: drawn on a terminal,
    /// hidden under `--quiet`, in CI and when stderr is redirected.
    pub fn progress_bar(&self, unit: &str, len: u64, done: u64) -> indicatif::ProgressBar {
        use std::io::IsTerminal;
        if self.quiet || !std::io::stderr().is_terminal() {
            return indicatif::ProgressBar::hidden();
        }
        let bar = indicatif::ProgressBar::new(len);
        bar.set_style(
            indicatif::ProgressStyle::with_template(&format!(
                "{{bar:30}} {{pos}}/{{len}} {unit}  {{msg}}  [{{elapsed_precise}}, ETA {{eta}}]"
            ))
            .expect("the template is valid"),
        );
        bar.set_position(done);
        bar
    }

    /// Path of the robot assets.
    pub fn assets(&self) -> &Path {
        &self.assets
    }
}
