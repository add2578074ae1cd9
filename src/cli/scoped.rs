//! The flags that only some commands take: `--objects-dir` (the commands that load objects)
//! and `--split` (those that read the train/test split). Each command's `--help` lists them only
//! where they apply (they are flattened into its flags); given before the command's name
//! (`graspmap --split FILE eval ...`), as scripts have always written them, they are accepted for
//! the commands that take them and refused, naming the flag, for the others.

use std::path::PathBuf;

use anyhow::bail;
use clap::Args;

/// `--objects-dir`.
#[derive(Debug, Args, Clone, Default)]
pub(crate) struct ObjectsArg {
    /// Directory of object models, each <Name>/model.urdf [default: the 15 bundled models].
    #[arg(long = "objects-dir", value_name = "DIR")]
    pub(crate) objects_dir: Option<PathBuf>,
}

/// `--split`.
#[derive(Debug, Args, Clone, Default)]
pub(crate) struct SplitArg {
    /// Train/test split JSON {"train": [..], "test": [..]} [default: <objects-dir>/split.json].
    #[arg(long = "split", value_name = "FILE")]
    pub(crate) split: Option<PathBuf>,
}

/// Both, for the commands that load the split's objects.
#[derive(Debug, Args, Clone, Default)]
pub(crate) struct ObjectsAndSplit {
    #[command(flatten)]
    pub(crate) objects: ObjectsArg,
    #[command(flatten)]
    pub(crate) split: SplitArg,
}

/// The scoped flags one command takes (`None`: it does not take that flag), as given after its
/// name.
#[derive(Debug, Default)]
pub(crate) struct Scoped<'a> {
    pub(crate) objects: Option<&'a ObjectsArg>,
    pub(crate) split: Option<&'a SplitArg>,
}

/// The scoped flags, resolved from both places they may be given.
#[derive(Debug, Default)]
pub(crate) struct Resolved {
    pub(crate) objects_dir: Option<PathBuf>,
    pub(crate) split: Option<PathBuf>,
}

/// The commands that take each flag, for the refusal.
const OBJECTS_USERS: &str = "scene, grasp, label, eval, collect and improve load objects";
const SPLIT_USERS: &str = "label, eval, collect and improve read the split";

/// One flag from before the command's name (`before`) and after it (`after`: `None` when the
/// command does not take it).
fn one<T>(
    flag: &str,
    command: &str,
    users: &str,
    before: Option<T>,
    after: Option<Option<T>>,
) -> anyhow::Result<Option<T>> {
    match (before, after) {
        (Some(_), None) => {
            bail!("--{flag} is not used by `graspmap {command}` ({users}); leave it out")
        }
        (Some(_), Some(Some(_))) => bail!(
            "--{flag} is given twice, before and after `{command}`; give it once (after the command's name)"
        ),
        (before, Some(after)) => Ok(after.or(before)),
        (None, None) => Ok(None),
    }
}

impl Scoped<'_> {
    /// Merges the flags given before the command's name with those given after it, refusing a
    /// flag the command does not take and one given in both places.
    pub(crate) fn resolve(&self, command: &str, before: Resolved) -> anyhow::Result<Resolved> {
        Ok(Resolved {
            objects_dir: one(
                "objects-dir",
                command,
                OBJECTS_USERS,
                before.objects_dir,
                self.objects.map(|a| a.objects_dir.clone()),
            )?,
            split: one(
                "split",
                command,
                SPLIT_USERS,
                before.split,
                self.split.map(|a| a.split.clone()),
            )?,
        })
    }
}

impl ObjectsAndSplit {
    /// Both flags taken.
    pub(crate) fn scoped(&self) -> Scoped<'_> {
        Scoped {
            objects: Some(&self.objects),
            split: Some(&self.split),
        }
    }
}
