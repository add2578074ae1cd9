//! The grasp-label dataset in the reference tool's layout (docs/data.md): `labels.json` plus one RGB image per label.
//!
//! `labels.json` maps each object to its labels `[x, y, angle]`, in the order of the images
//! `<Object>_<k>_rgb.png` (k from 1). Writes go through a temporary file and a rename, image
//! first, so a killed run leaves a valid `labels.json` whose every image exists.

use std::path::{Path, PathBuf};

use anyhow::Context;
use serde::Serialize;

use super::atomic::{save_image_atomic, write_atomic};
use super::progress::{Progress, PROGRESS_FILE};
use crate::grasp::{PixelGrasp, IMAGE_SIZE};

/// The labels file name inside the labels directory.
pub(crate) const LABELS_FILE: &str = "labels.json";
/// File-name ending of a label's depth image, after `<Object>_<k>` (data::depth_files checks them).
pub(crate) const DEPTH_SUFFIX: &str = "_depth.png";

/// One labelled grasp: integer pixel and angle in degrees.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Label {
    /// Column.
    pub x: u32,
    /// Row.
    pub y: u32,
    /// Image angle in degrees, [0, 180).
    pub angle: f32,
}

impl From<PixelGrasp> for Label {
    fn from(g: PixelGrasp) -> Self {
        Label {
            x: g.u,
            y: g.v,
            angle: g.angle_deg,
        }
    }
}

impl From<Label> for PixelGrasp {
    fn from(l: Label) -> Self {
        PixelGrasp {
            u: l.x,
            v: l.y,
            angle_deg: l.angle,
        }
    }
}

/// All labels, per object, in the order objects were first labelled.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Labels {
    entries: Vec<(String, Vec<Label>)>,
}

/// Problems with a labels file or dataset.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LabelError {
    /// The file is not JSON.
    #[error("{path}: not valid JSON: {error}")]
    NotJson { path: PathBuf, error: String },
    /// The top level is not an object of objects' labels.
    #[error("{path}: expected an object {{\"<Object>\": [[x, y, angle], ...]}}")]
    NotAnObject { path: PathBuf },
    /// An object's value is not a list.
    #[error("{path}: '{object}' must map to a list of [x, y, angle]")]
    NotAList { path: PathBuf, object: String },
    /// One label is not a valid `[x, y, angle]`.
    #[error("{path}: '{object}' label {index}: {problem}")]
    BadLabel {
        path: PathBuf,
        object: String,
        /// 1-based, as in the file's list.
        index: usize,
        problem: String,
    },
}

impl Labels {
    /// Labels of one object (empty when it has none).
    pub fn of(&self, object: &str) -> &[Label] {
        self.entries
            .iter()
            .find(|(name, _)| name == object)
            .map_or(&[], |(_, labels)| labels.as_slice())
    }

    /// Objects with their labels.
    pub fn iter(&self) -> impl Iterator<Item = (&str, &[Label])> {
        self.entries
            .iter()
            .filter(|(_, labels)| !labels.is_empty())
            .map(|(name, labels)| (name.as_str(), labels.as_slice()))
    }

    /// Total number of labels.
    pub fn len(&self) -> usize {
        self.entries.iter().map(|(_, l)| l.len()).sum()
    }

    /// True when there are no labels.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Puts `order`'s objects first, in that order (giving a place to those without labels yet),
    /// and any others after them as they were. Objects without labels are not written, so a
    /// file left by a killed run lists whichever object was labelled first; arranged like this,
    /// the resumed file's order follows the split, whoever labels first.
    pub(crate) fn arrange(&mut self, order: &[String]) {
        let mut rest = std::mem::take(&mut self.entries);
        for object in order {
            let labels = match rest.iter().position(|(name, _)| name == object) {
                Some(i) => rest.remove(i).1,
                None => Vec::new(),
            };
            self.entries.push((object.clone(), labels));
        }
        self.entries.extend(rest);
    }

    /// Takes the last label of `object` away again (undoing a [`Labels::push`]).
    pub(crate) fn pop(&mut self, object: &str) {
        if let Some((_, list)) = self.entries.iter_mut().find(|(name, _)| name == object) {
            list.pop();
        }
        self.entries.retain(|(_, list)| !list.is_empty());
    }

    /// Removes `object`'s label k (1-based), keeping the others in order.
    pub(crate) fn remove(&mut self, object: &str, k: usize) {
        if let Some((_, list)) = self.entries.iter_mut().find(|(name, _)| name == object) {
            if (1..=list.len()).contains(&k) {
                list.remove(k - 1);
            }
        }
    }

    /// Appends a label for `object`; returns its 1-based index k.
    pub(crate) fn push(&mut self, object: &str, label: Label) -> usize {
        match self.entries.iter_mut().find(|(name, _)| name == object) {
            Some((_, labels)) => {
                labels.push(label);
                labels.len()
            }
            None => {
                self.entries.push((object.to_owned(), vec![label]));
                1
            }
        }
    }

    /// Parses `labels.json` text (the reference tool's format; `path` is for messages).
    pub fn parse(text: &str, path: &Path) -> Result<Self, LabelError> {
        let path = || path.to_owned();
        let value: serde_json::Value =
            serde_json::from_str(text).map_err(|e| LabelError::NotJson {
                path: path(),
                error: e.to_string(),
            })?;
        let map = value
            .as_object()
            .ok_or_else(|| LabelError::NotAnObject { path: path() })?;
        let mut labels = Labels::default();
        for (object, list) in map {
            let list = list.as_array().ok_or_else(|| LabelError::NotAList {
                path: path(),
                object: object.clone(),
            })?;
            let mut parsed = Vec::with_capacity(list.len());
            for (i, entry) in list.iter().enumerate() {
                let label = parse_label(entry).map_err(|problem| LabelError::BadLabel {
                    path: path(),
                    object: object.clone(),
                    index: i + 1,
                    problem,
                })?;
                parsed.push(label);
            }
            labels.entries.push((object.clone(), parsed));
        }
        Ok(labels)
    }

    /// The reference format: 4-space indent, integer x/y, float angles.
    pub fn to_json(&self) -> String {
        let map: serde_json::Map<String, serde_json::Value> = self
            .entries
            .iter()
            .filter(|(_, labels)| !labels.is_empty())
            .map(|(object, labels)| {
                let list = labels
                    .iter()
                    .map(|l| serde_json::json!([l.x, l.y, l.angle as f64]))
                    .collect();
                (object.clone(), serde_json::Value::Array(list))
            })
            .collect();
        let mut out = Vec::new();
        let formatter = serde_json::ser::PrettyFormatter::with_indent(b"    ");
        let mut serializer = serde_json::Serializer::with_formatter(&mut out, formatter);
        serde_json::Value::Object(map)
            .serialize(&mut serializer)
            .expect("serialising JSON values to memory cannot fail");
        out.push(b'\n');
        String::from_utf8(out).expect("serde_json writes UTF-8")
    }
}

/// One `[x, y, angle]` entry; x and y integers inside the image, the angle normalised.
fn parse_label(entry: &serde_json::Value) -> Result<Label, String> {
    let triple = entry
        .as_array()
        .filter(|a| a.len() == 3)
        .ok_or_else(|| format!("must be [x, y, angle], got {entry}"))?;
    let number = |v: &serde_json::Value, what: &str| {
        v.as_f64()
            .ok_or_else(|| format!("{what} = {v} is not a number"))
    };
    let grasp = PixelGrasp::checked(
        number(&triple[0], "x")?,
        number(&triple[1], "y")?,
        number(&triple[2], "angle")?,
    )
    .map_err(|e| e.to_string())?;
    Ok(Label::from(grasp))
}

/// A labels directory on disk.
#[derive(Debug, Clone)]
pub struct LabelStore {
    dir: PathBuf,
}

impl LabelStore {
    /// The store in `dir` (usually DATA/labels).
    pub fn new(dir: impl Into<PathBuf>) -> Self {
        Self { dir: dir.into() }
    }

    /// Its directory.
    pub(crate) fn dir(&self) -> &Path {
        &self.dir
    }

    /// Path of labels.json.
    pub fn labels_path(&self) -> PathBuf {
        self.dir.join(LABELS_FILE)
    }

    /// Path of the k-th image of an object.
    pub fn image_path(&self, object: &str, k: usize) -> PathBuf {
        self.dir.join(format!("{object}_{k}_rgb.png"))
    }

    /// Path of the depth image beside the k-th image of an object: a sidecar of
    /// `<Object>_<k>_rgb.png` with the same `<Object>_<k>` stem (docs/data.md).
    pub(crate) fn depth_path(&self, object: &str, k: usize) -> PathBuf {
        self.dir.join(format!("{object}_{k}{}", DEPTH_SUFFIX))
    }

    /// Deletes temporary files a killed run left behind (they are never read, but would
    /// otherwise pile up beside the dataset).
    pub(crate) fn remove_stale_temporaries(&self) -> anyhow::Result<()> {
        let Ok(entries) = std::fs::read_dir(&self.dir) else {
            return Ok(());
        };
        for entry in entries.flatten() {
            let name = entry.file_name();
            let name = name.to_string_lossy();
            if name.starts_with('.') && name.contains(".tmp-") {
                std::fs::remove_file(entry.path())
                    .with_context(|| format!("removing {}", entry.path().display()))?;
            }
        }
        Ok(())
    }

    /// Reads labels.json; an absent file is an empty dataset.
    pub fn load(&self) -> anyhow::Result<Labels> {
        let path = self.labels_path();
        match std::fs::read_to_string(&path) {
            Ok(text) => Ok(Labels::parse(&text, &path)?),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(Labels::default()),
            Err(e) => Err(e).with_context(|| format!("reading {}", path.display())),
        }
    }

    /// Appends one label: its depth image (when given) first, then the image, then
    /// labels.json, each atomically, so every listed image has its depth beside it.
    pub(crate) fn append(
        &self,
        labels: &mut Labels,
        object: &str,
        label: Label,
        image: &image::RgbImage,
        depth: Option<&super::input::DepthMm>,
    ) -> anyhow::Result<usize> {
        let k = labels.of(object).len() + 1;
        let image_path = self.image_path(object, k);
        if let Some(depth) = depth {
            save_image_atomic(depth, &self.depth_path(object, k))?;
        }
        if let Err(e) = save_image_atomic(image, &image_path) {
            // No image, no label: take the depth away again (`--check` would call it extra).
            if depth.is_some() {
                let _ = std::fs::remove_file(self.depth_path(object, k));
            }
            return Err(e);
        }
        labels.push(object, label);
        if let Err(e) = write_atomic(&self.labels_path(), labels.to_json().as_bytes()) {
            // labels.json still lists k - 1 images: take the k-th away again, so that the
            // dataset on disk is exactly the one before this append (`--check` passes).
            let _ = std::fs::remove_file(&image_path);
            if depth.is_some() {
                let _ = std::fs::remove_file(self.depth_path(object, k));
            }
            labels.pop(object);
            return Err(e);
        }
        Ok(k)
    }

    /// Removes labels.json and every label image (for `--force`).
    pub(crate) fn clear(&self) -> anyhow::Result<()> {
        let Ok(entries) = std::fs::read_dir(&self.dir) else {
            return Ok(());
        };
        for entry in entries.flatten() {
            let name = entry.file_name();
            let name = name.to_string_lossy();
            if name == LABELS_FILE
                || name.ends_with("_rgb.png")
                || name.ends_with(DEPTH_SUFFIX)
                || name == PROGRESS_FILE
            {
                std::fs::remove_file(entry.path())
                    .with_context(|| format!("removing {}", entry.path().display()))?;
            }
        }
        Ok(())
    }

    /// Every problem with the dataset, one line each; empty when it is sound.
    pub fn check(&self, known_objects: &[String]) -> Vec<String> {
        let mut problems = Vec::new();
        let labels_path = self.labels_path();
        let text = match std::fs::read_to_string(&labels_path) {
            Ok(text) => text,
            Err(e) => {
                return vec![format!("{}: {e}", labels_path.display())];
            }
        };
        let value: serde_json::Value = match serde_json::from_str(&text) {
            Ok(value) => value,
            Err(e) => return vec![format!("{}: not valid JSON: {e}", labels_path.display())],
        };
        let Some(map) = value.as_object() else {
            return vec![format!(
                "{}: expected an object {{\"<Object>\": [[x, y, angle], ...]}}",
                labels_path.display()
            )];
        };
        let mut expected = std::collections::HashSet::new();
        for (object, list) in map {
            if !known_objects.iter().any(|k| k == object) {
                problems.push(format!(
                    "{}: unknown object '{object}' (known: {})",
                    labels_path.display(),
                    known_objects.join(", ")
                ));
            }
            let Some(list) = list.as_array() else {
                problems.push(format!(
                    "{}: '{object}' must map to a list of [x, y, angle]",
                    labels_path.display()
                ));
                continue;
            };
            for (i, entry) in list.iter().enumerate() {
                let k = i + 1;
                if let Err(message) = parse_label(entry) {
                    problems.push(format!(
                        "{}: '{object}' label {k}: {message}",
                        labels_path.display()
                    ));
                }
                let path = self.image_path(object, k);
                expected.insert(path.clone());
                if let Some(problem) = image_problem(&path) {
                    problems.push(problem);
                }
            }
        }
        if let Ok(entries) = std::fs::read_dir(&self.dir) {
            let mut extra: Vec<PathBuf> = entries
                .flatten()
                .map(|e| e.path())
                .filter(|p| p.to_string_lossy().ends_with("_rgb.png") && !expected.contains(p))
                .collect();
            extra.sort();
            for path in extra {
                problems.push(format!(
                    "{}: extra image not listed in {LABELS_FILE}",
                    path.display()
                ));
            }
        }
        problems
    }
}

/// What is wrong with a label's image, as training would find it: missing, unreadable or cut
/// short (every pixel is decoded), or not 128 × 128 8-bit RGB.
fn image_problem(path: &Path) -> Option<String> {
    if !path.exists() {
        return Some(format!("{}: missing image", path.display()));
    }
    let decoded = match image::open(path) {
        Ok(decoded) => decoded,
        Err(e) => {
            return Some(format!(
                "{}: unreadable or truncated image ({e}); restore it, or relabel",
                path.display()
            ))
        }
    };
    let (w, h, color) = (decoded.width(), decoded.height(), decoded.color());
    if (w, h) != (IMAGE_SIZE, IMAGE_SIZE) {
        return Some(format!(
            "{}: image is {w}×{h}, expected {IMAGE_SIZE}×{IMAGE_SIZE}",
            path.display()
        ));
    }
    if color != image::ColorType::Rgb8 {
        return Some(format!(
            "{}: image is {color:?} ({} bits per pixel), expected 8-bit RGB (Rgb8)",
            path.display(),
            color.bits_per_pixel()
        ));
    }
    None
}

impl LabelStore {
    /// Reads progress.json, if any.
    pub(crate) fn load_progress(&self) -> anyhow::Result<Option<Progress>> {
        Progress::load(&self.dir)
    }

    /// Writes progress.json atomically.
    pub(crate) fn save_progress(&self, progress: &Progress) -> anyhow::Result<()> {
        progress.save(&self.dir)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arranged_labels_follow_the_split_whoever_was_labelled_first() {
        // A run killed after the brick's first label, before the ball's.
        let text = r#"{"YcbFoamBrick": [[50, 72, 135.0]], "YcbOther": [[1, 2, 0.0]]}"#;
        let mut labels = Labels::parse(text, Path::new("labels.json")).unwrap();
        labels.arrange(&["YcbTennisBall".to_owned(), "YcbFoamBrick".to_owned()]);
        let ball = Label {
            x: 83,
            y: 75,
            angle: 90.0,
        };
        labels.push("YcbTennisBall", ball);
        let order: Vec<&str> = labels.iter().map(|(name, _)| name).collect();
        assert_eq!(order, ["YcbTennisBall", "YcbFoamBrick", "YcbOther"]);
        assert_eq!(labels.of("YcbFoamBrick").len(), 1);
        let json = labels.to_json();
        assert!(
            json.find("YcbTennisBall") < json.find("YcbFoamBrick"),
            "{json}"
        );
    }

    #[test]
    fn labels_round_trip_through_the_reference_format() {
        let mut labels = Labels::default();
        labels.push(
            "YcbHammer",
            Label {
                x: 75,
                y: 64,
                angle: 45.0,
            },
        );
        labels.push(
            "YcbTomatoSoupCan",
            Label {
                x: 64,
                y: 58,
                angle: 0.0,
            },
        );
        labels.push(
            "YcbHammer",
            Label {
                x: 61,
                y: 70,
                angle: 112.5,
            },
        );
        let text = labels.to_json();
        assert!(
            text.contains("\n    \"YcbHammer\": [\n        [\n            75,"),
            "{text}"
        );
        assert!(text.contains("45.0"), "angles are floats: {text}");
        let back = Labels::parse(&text, Path::new("labels.json")).unwrap();
        assert_eq!(back, labels);
        assert_eq!(back.of("YcbHammer").len(), 2);
        assert_eq!(back.len(), 3);
    }

    #[test]
    fn bad_values_are_named_in_the_error() {
        let path = Path::new("labels.json");
        for (text, needle) in [
            (r#"{"A": [[128, 3, 0.0]]}"#, "x = 128"),
            (r#"{"A": [[3, -1, 0.0]]}"#, "y = -1"),
            (r#"{"A": [[3, 4.5, 0.0]]}"#, "y = 4.5"),
            (r#"{"A": [[3, 4, "left"]]}"#, "angle"),
            (r#"{"A": [[3, 4]]}"#, "[x, y, angle]"),
            (r#"{"A": 3}"#, "list"),
            (r#"[1, 2]"#, "expected an object"),
            (r#"{"A": [[3, 4, 0.0]"#, "not valid JSON"),
        ] {
            let err = Labels::parse(text, path).unwrap_err().to_string();
            assert!(err.contains(needle), "{text}: {err}");
            assert!(err.contains("labels.json"), "{err}");
        }
    }

    #[test]
    fn angles_are_normalised_on_load() {
        let labels =
            Labels::parse(r#"{"A": [[1, 2, -22.5], [1, 2, 180.0]]}"#, Path::new("l")).unwrap();
        assert_eq!(labels.of("A")[0].angle, 157.5);
        assert_eq!(labels.of("A")[1].angle, 0.0);
    }
}

#[cfg(test)]
mod fuzz {
    use std::path::Path;

    use proptest::prelude::*;

    use crate::data::fuzzing::{check, config, edits, mutate, text};

    const LABELS: &str = include_str!("../../tests/fixtures/reference-labels/labels.json");

    proptest! {
        #![proptest_config(config())]

        #[test]
        fn fuzz_json_labels(edits in edits()) {
            let input = text(&mutate(LABELS.as_bytes(), &edits));
            check(|| crate::data::labels::Labels::parse(&input, Path::new("labels.json")))?;
        }
    }
}
