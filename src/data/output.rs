//! Outputs checked before the work starts: every command asks here, before its first scene,
//! epoch or round, whether each file and folder it will write can be written, so that a
//! read-only data directory or a mistyped `--json` path fails in a second with one line that
//! names the path, says why and gives the fix, not after an hour of simulation.
//!
//! The check creates the folders an output needs (a missing parent folder is created, not
//! refused) and probes each folder with a file that it removes at once. [`RunFiles::check`] also
//! makes sure that no output replaces one of the command's inputs or a file graspmap reads as
//! state (labels, progress, trial stores, models, improve summaries: never, even with
//! `--force`), another output of the same run, or an existing file that is not an earlier
//! output of the same kind (unless `--force`; a `--json` report never replaces anything but an
//! earlier report of the same command).

use std::io::ErrorKind;
use std::path::{Path, PathBuf};

/// Why an output cannot be written.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// The path names a folder where a file is wanted.
    #[error("{what} {path} is a directory; give the path of a file (inside it, or elsewhere)")]
    IsDirectory { what: String, path: PathBuf },
    /// The output is one of the command's inputs.
    #[error("{what} {path} is also {input}; write the output to another path (--force never replaces an input)")]
    IsInput {
        what: String,
        path: PathBuf,
        input: String,
    },
    /// The file is one that graspmap reads as state.
    #[error("{what} {path} is {state}, which graspmap reads; write the output to another path (--force never replaces it)")]
    IsState {
        what: String,
        path: PathBuf,
        state: String,
    },
    /// Two outputs of one run name the same file.
    #[error("{what} and {other} both name {path}; give each output its own path")]
    SameAsOther {
        what: String,
        other: String,
        path: PathBuf,
    },
    /// The file exists, and this run may not replace it.
    #[error("{what} {path} already exists{why}; {fix}")]
    Exists {
        what: String,
        path: PathBuf,
        why: String,
        fix: &'static str,
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
/// (stdout) always passes. A missing folder on the way is created.
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
    if !parent.is_dir() {
        return check_output_dir(&parent, what).map_err(|e| match e {
            OutputError::NotWritable {
                what,
                folder,
                reason,
                fix,
                ..
            } => OutputError::NotWritable {
                what,
                path: path.to_path_buf(),
                folder,
                reason,
                fix,
            },
            OutputError::NotAFolder { what, blocker, .. } => OutputError::NotAFolder {
                what,
                path: path.to_path_buf(),
                blocker,
            },
            other => other,
        });
    }
    probe(&parent, path, what)
}

/// What an existing file at an output's path may be replaced as.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Existing {
    /// The command's own file under the data directory (a default path): replaced.
    Replace,
    /// Replaced when it is an earlier output of this kind, else only with `--force`.
    Own(Kind),
    /// Replaced only when it is an earlier output of this kind; `--force` does not reach it.
    Earlier(Kind),
    /// Replaced only with `--force`.
    Force,
}

/// Kinds of output that a rerun replaces without `--force`: what graspmap wrote there before.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Kind {
    /// A `--json` report of this command (`"schema": "graspmap.<command>/N"`).
    JsonReport(&'static str),
    /// A `--record` video (MP4 or GIF).
    Video,
    /// `graspmap report`'s page.
    ReportPage,
    /// `label --interactive`'s 512 × 512 preview image.
    Preview,
}

impl Kind {
    fn name(self) -> String {
        match self {
            Kind::JsonReport(command) => format!("graspmap {command} report"),
            Kind::Video => "video".to_owned(),
            Kind::ReportPage => "graspmap report page".to_owned(),
            Kind::Preview => "labelling preview".to_owned(),
        }
    }

    /// Whether the file at `path` is an earlier output of this kind.
    pub(crate) fn holds(self, path: &Path) -> bool {
        use std::io::Read as _;
        match self {
            Kind::Preview => return image::image_dimensions(path).is_ok_and(|d| d == (512, 512)),
            Kind::JsonReport(command) => {
                return schema_of(path).is_some_and(|s| {
                    s.strip_prefix(&format!("graspmap.{command}/"))
                        .is_some_and(|v| !v.is_empty() && v.bytes().all(|b| b.is_ascii_digit()))
                })
            }
            _ => {}
        }
        let mut head = Vec::new();
        let read = std::fs::File::open(path).and_then(|f| f.take(2048).read_to_end(&mut head));
        if read.is_err() {
            return false;
        }
        let text = String::from_utf8_lossy(&head);
        match self {
            Kind::Video => head.starts_with(b"GIF8") || head.get(4..8) == Some(b"ftyp"),
            Kind::ReportPage => text.contains("<title>graspmap run report</title>"),
            Kind::Preview | Kind::JsonReport(_) => false,
        }
    }
}

/// The commands whose `--json` reports carry the schema `graspmap.<command>/N`. Every other
/// graspmap schema (label progress, trial stores, checkpoints, …) names a file that graspmap
/// reads as state.
const REPORTING_COMMANDS: [&str; 11] = [
    "scene", "grasp", "label", "train", "eval", "collect", "merge", "improve", "predict", "report",
    "bench",
];

/// Largest JSON file read to tell what it is; graspmap's own state files are far smaller.
const MAX_JSON_PEEK: u64 = 64 << 20;

/// The file as JSON, when it is a JSON file of reasonable size.
fn json_of(path: &Path) -> Option<serde_json::Value> {
    let meta = std::fs::metadata(path).ok()?;
    if !meta.is_file() || meta.len() > MAX_JSON_PEEK {
        return None;
    }
    serde_json::from_slice(&std::fs::read(path).ok()?).ok()
}

/// The `schema` of a JSON file, when it has one.
fn schema_of(path: &Path) -> Option<String> {
    json_of(path)?.get("schema")?.as_str().map(str::to_owned)
}

/// The state folders of a data directory: every file in them is read by some command.
const STATE_FOLDERS: [(&str, &str); 4] = [
    ("labels", "part of the labelled dataset"),
    ("trials", "part of the trial store"),
    ("improve", "part of improve's rounds"),
    ("reports", "a report that eval keeps for graspmap report"),
];

/// What the existing file at `path` is, when graspmap reads it as state: a file in one of the
/// data directory's state folders, a model file beside the model, a checkpoint, or a JSON file
/// whose schema or shape is that of one of graspmap's own state files (wherever it lies).
pub(crate) fn state_of(path: &Path, data: Option<&Path>) -> Option<String> {
    if !path.is_file() {
        return None;
    }
    if let Some(data) = data {
        let id = identity(path);
        let data = identity(data);
        for (folder, words) in STATE_FOLDERS {
            if id.starts_with(data.join(folder)) {
                return Some(format!("{words} in {}", data.join(folder).display()));
            }
        }
        if id.parent() == Some(&data.join("affordance")) {
            return Some(format!(
                "part of the model in {}",
                data.join("affordance").display()
            ));
        }
    }
    let extension = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    if extension.as_deref() == Some("safetensors") {
        return Some("a model checkpoint".to_owned());
    }
    let json = json_of(path)?;
    if let Some(schema) = json.get("schema").and_then(|s| s.as_str()) {
        let command = schema
            .strip_prefix("graspmap.")
            .and_then(|s| s.split('/').next());
        return match command {
            Some(c) if !REPORTING_COMMANDS.contains(&c) => {
                Some(format!("a graspmap state file (schema {schema})"))
            }
            _ => None,
        };
    }
    state_shape(&json)
}

/// graspmap's state files without a schema, told by their shape: labels.json (every value a
/// list of `[x, y, angle]`), a trial store's scene (`trials.json`) and improve's summaries.
fn state_shape(json: &serde_json::Value) -> Option<String> {
    let has = |v: &serde_json::Value, keys: &[&str]| keys.iter().all(|k| v.get(k).is_some());
    let summary = |v: &serde_json::Value| has(v, &["round", "collected_with", "model"]);
    if summary(json)
        || json
            .as_array()
            .is_some_and(|a| !a.is_empty() && a.iter().all(summary))
    {
        return Some("a summary of improve's rounds".to_owned());
    }
    if has(json, &["scene", "drop_seed", "complete", "trials"]) {
        return Some("a scene of a trial store".to_owned());
    }
    let is_label = |v: &serde_json::Value| {
        v.as_array()
            .is_some_and(|a| a.len() == 3 && a.iter().all(serde_json::Value::is_number))
    };
    let labels = json.as_object().is_some_and(|o| {
        !o.is_empty()
            && o.values()
                .all(|v| v.as_array().is_some_and(|l| l.iter().all(is_label)))
    });
    labels.then(|| "a labels file (labels.json)".to_owned())
}

/// One file a command will write: its path, the flag that names it in errors, and what an
/// existing file there may be.
#[derive(Debug, Clone)]
pub(crate) struct FileOutput {
    pub(crate) path: PathBuf,
    pub(crate) what: String,
    pub(crate) existing: Existing,
}

impl FileOutput {
    pub(crate) fn new(path: &Path, what: &str, existing: Existing) -> Self {
        Self {
            path: path.to_path_buf(),
            what: what.to_owned(),
            existing,
        }
    }
}

/// The files one run reads and writes, checked together before the work starts.
#[derive(Debug, Clone, Default)]
pub(crate) struct RunFiles {
    /// Files (or folders) the run reads, each with the words that name it.
    pub(crate) inputs: Vec<(String, PathBuf)>,
    /// Files the run writes.
    pub(crate) outputs: Vec<FileOutput>,
    /// Files no explicitly named output may replace (the kept eval reports).
    pub(crate) protected: Vec<(String, PathBuf)>,
    /// `--force`, where the command has it for its outputs (`None` where it does not).
    pub(crate) force: Option<bool>,
    /// The data directory, whose state folders no output may replace a file in.
    pub(crate) data: Option<PathBuf>,
}

impl RunFiles {
    /// An input, when given.
    pub(crate) fn input(&mut self, words: &str, path: Option<&Path>) {
        if let Some(path) = path {
            self.inputs.push((words.to_owned(), path.to_path_buf()));
        }
    }

    /// An output, when given.
    pub(crate) fn output(&mut self, path: Option<&Path>, what: &str, existing: Existing) {
        if let Some(path) = path.filter(|p| *p != Path::new("-")) {
            self.outputs.push(FileOutput::new(path, what, existing));
        }
    }

    /// Every file in the kept reports' folder, `data/reports`, protected.
    pub(crate) fn protect_kept_reports(&mut self, data: &Path) {
        let Ok(entries) = std::fs::read_dir(data.join("reports")) else {
            return;
        };
        let mut files: Vec<PathBuf> = entries
            .flatten()
            .map(|e| e.path())
            .filter(|p| p.is_file())
            .collect();
        files.sort();
        for path in files {
            let words = "a report that eval keeps for graspmap report".to_owned();
            self.protected.push((words, path));
        }
    }

    /// Checks every output: not an input (never, even with --force), not a protected file
    /// unless it is the command's own default path, not another output, not a folder, not an
    /// existing file it may not replace; and writable, its missing folders created.
    pub(crate) fn check(&self) -> Result<(), OutputError> {
        let mut seen: Vec<(PathBuf, &FileOutput)> = Vec::new();
        for output in &self.outputs {
            let path = &output.path;
            let what = &output.what;
            let id = identity(path);
            let protected = self
                .protected
                .iter()
                .filter(|_| output.existing != Existing::Replace);
            for (words, input) in self.inputs.iter().chain(protected) {
                if identity(input) == id {
                    return Err(OutputError::IsInput {
                        what: what.clone(),
                        path: path.clone(),
                        input: words.clone(),
                    });
                }
            }
            if let Some((_, other)) = seen.iter().find(|(other, _)| *other == id) {
                return Err(OutputError::SameAsOther {
                    what: other.what.clone(),
                    other: what.clone(),
                    path: path.clone(),
                });
            }
            seen.push((id, output));
            if path.is_dir() {
                return Err(OutputError::IsDirectory {
                    what: what.clone(),
                    path: path.clone(),
                });
            }
            // An earlier preview, video or page of the output's own kind is the command's own,
            // wherever it lies (label --interactive's preview sits in the labels folder).
            let own_kind = match output.existing {
                Existing::Own(kind) | Existing::Earlier(kind) => {
                    !matches!(kind, Kind::JsonReport(_)) && kind.holds(path)
                }
                _ => false,
            };
            let state = state_of(path, self.data.as_deref()).filter(|_| !own_kind);
            if let Some(state) = state {
                return Err(OutputError::IsState {
                    what: what.clone(),
                    path: path.clone(),
                    state,
                });
            }
            if path.symlink_metadata().is_ok() {
                self.check_replace(output)?;
            }
            check_output_file(path, what)?;
        }
        Ok(())
    }

    /// Whether an output may replace the file already at its path.
    fn check_replace(&self, output: &FileOutput) -> Result<(), OutputError> {
        let path = &output.path;
        let forced = self.force == Some(true);
        let (allowed, why) = match output.existing {
            Existing::Replace => (true, String::new()),
            Existing::Force => (forced, String::new()),
            Existing::Own(kind) => (
                forced || kind.holds(path),
                format!(" and is not an earlier {}", kind.name()),
            ),
            Existing::Earlier(kind) => (
                kind.holds(path),
                format!(" and is not an earlier {}", kind.name()),
            ),
        };
        if allowed {
            return Ok(());
        }
        Err(OutputError::Exists {
            what: output.what.clone(),
            path: path.clone(),
            why,
            fix: match (self.force, output.existing) {
                (Some(_), Existing::Own(_) | Existing::Force) => {
                    "pass --force to replace it, or choose another path"
                }
                _ => "delete it, or choose another path",
            },
        })
    }
}

/// A path as the file system knows it, so that `a.png`, `./a.png` and a link to it compare
/// equal: canonical where it exists, else its folder's canonical path and its name.
pub(crate) fn identity(path: &Path) -> PathBuf {
    if let Ok(real) = std::fs::canonicalize(path) {
        return real;
    }
    let name = path.file_name();
    match (std::fs::canonicalize(parent_of(path)), name) {
        (Ok(folder), Some(name)) => folder.join(name),
        _ => std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf()),
    }
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
        // A missing folder is created.
        let missing = dir.path().join("nope").join("r.json");
        check_output_file(&missing, "--json").unwrap();
        assert!(dir.path().join("nope").is_dir());
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
    fn a_json_report_replaces_only_its_own_command_s_and_never_state() {
        let dir = tempfile::tempdir().unwrap();
        let write = |name: &str, text: &str| {
            let path = dir.path().join(name);
            std::fs::write(&path, text).unwrap();
            path
        };
        let eval = write(
            "eval.json",
            r#"{"schema": "graspmap.eval/2", "results": {}}"#,
        );
        let progress = write("p.json", r#"{"schema": "graspmap.label-progress/2"}"#);
        let evaluation = write("e.json", r#"{"schema": "graspmap.evaluation/1"}"#);
        let labels = write("l.json", r#"{"YcbHammer": [[75, 64, 45.0]]}"#);
        let scene = write(
            "t.json",
            r#"{"scene": 0, "drop_seed": 1, "objects": [], "complete": true, "trials": []}"#,
        );
        let summary = write(
            "s.json",
            r#"[{"round": 1, "collected_with": "a", "model": "b"}]"#,
        );
        let mine = write("mine.json", r#"{"a": 1}"#);
        let weights = write("w.safetensors", "x");
        assert!(Kind::JsonReport("eval").holds(&eval));
        assert!(!Kind::JsonReport("train").holds(&eval));
        // A longer command name sharing the prefix is another command.
        assert!(!Kind::JsonReport("eval").holds(&evaluation));
        for state in [&progress, &evaluation, &labels, &scene, &summary, &weights] {
            assert!(state_of(state, None).is_some(), "{state:?}");
        }
        for other in [&eval, &mine] {
            assert_eq!(state_of(other, None), None, "{other:?}");
        }
        // Inside a data directory's state folders, any file is state.
        let data = dir.path().join("data");
        std::fs::create_dir_all(data.join("labels")).unwrap();
        let image = data.join("labels").join("notes.txt");
        std::fs::write(&image, "x").unwrap();
        assert_eq!(state_of(&image, None), None);
        assert!(state_of(&image, Some(&data)).is_some());
        // The labelling preview is label's own, in the labels folder.
        let preview = data.join("labels").join("preview.png");
        image::RgbImage::new(512, 512).save(&preview).unwrap();
        let files = RunFiles {
            outputs: vec![FileOutput::new(
                &preview,
                "--preview",
                Existing::Own(Kind::Preview),
            )],
            data: Some(data.clone()),
            ..RunFiles::default()
        };
        files.check().unwrap();
        // Even with --force.
        let files = RunFiles {
            outputs: vec![FileOutput::new(&progress, "--out", Existing::Force)],
            force: Some(true),
            ..RunFiles::default()
        };
        let err = files.check().unwrap_err().to_string();
        assert!(err.contains("which graspmap reads"), "{err}");
    }

    #[test]
    fn the_reason_is_said_once_without_the_error_code() {
        let e = std::io::Error::from_raw_os_error(libc::EACCES);
        assert_eq!(reason(&e), "permission denied");
    }
}
