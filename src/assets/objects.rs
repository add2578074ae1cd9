//! Object models and the train/test split: bundled primitive compounds or imported mesh URDFs, resolved by name.

use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::assets::urdf::{Collision, UrdfError, UrdfFile, Visual};

/// Friction used when a URDF has no Bullet `<contact>` tag (Bullet's own default).
pub const DEFAULT_FRICTION: f32 = 0.5;

/// A graspable object: one rigid body with compound collision geometry.
#[derive(Debug, Clone)]
pub struct ObjectModel {
    /// Name (the directory name, e.g. `YcbMustardBottle`).
    pub(crate) name: String,
    /// Mass in kg.
    pub mass: f32,
    /// Lateral friction coefficient μ (combined with the pads' 1.0 by multiplication).
    pub friction: f32,
    /// Collision pieces in the object frame.
    pub collisions: Vec<Collision>,
    /// Drawable pieces in the object frame.
    pub visuals: Vec<Visual>,
}

/// Failures finding or reading object models and split files.
#[derive(Debug, thiserror::Error)]
pub enum ObjectError {
    /// No `<dir>/<name>/model.urdf`.
    #[error(
        "unknown object '{name}'{}; {}",
        in_library(library),
        known_list(library, known)
    )]
    Unknown {
        name: String,
        /// Where the models come from: a directory, or `None` for the bundled ones.
        library: Option<PathBuf>,
        known: Vec<String>,
    },
    /// The object's URDF is broken.
    #[error(transparent)]
    Urdf(#[from] UrdfError),
    /// The URDF has no usable link.
    #[error("{path}: {message}")]
    Invalid { path: PathBuf, message: String },
    /// The split file cannot be read or parsed.
    #[error("split file {path}: {message} (expected {{\"train\": [..], \"test\": [..]}})")]
    Split { path: PathBuf, message: String },
    /// The split parses but names an object twice or one the library lacks.
    #[error("split file {path}: {message}")]
    SplitObjects { path: PathBuf, message: String },
}

/// " in DIR" for a directory of models; nothing for the bundled ones.
fn in_library(library: &Option<PathBuf>) -> String {
    library
        .as_ref()
        .map_or_else(String::new, |dir| format!(" in {}", dir.display()))
}

/// The objects a library knows, or what an empty one lacks.
fn known_list(library: &Option<PathBuf>, known: &[String]) -> String {
    match library {
        Some(dir) if known.is_empty() => format!(
            "{} holds no objects (each needs <Name>/model.urdf)",
            dir.display()
        ),
        _ => format!("known objects: {}", known.join(", ")),
    }
}

/// The bundled objects' folder under assets/.
const BUNDLED_OBJECTS: &str = "objects";

/// A catalogue of `<Name>/model.urdf` object models: the bundled one, or a directory on disk.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ObjectLibrary {
    /// `None` for the bundled models.
    dir: Option<PathBuf>,
}

impl ObjectLibrary {
    /// The fifteen bundled YCB-like models.
    pub fn bundled() -> Self {
        Self { dir: None }
    }

    /// A library rooted at `dir`.
    pub fn new(dir: impl Into<PathBuf>) -> Self {
        Self {
            dir: Some(dir.into()),
        }
    }

    /// The folder of the models; `None` for the bundled ones.
    pub(crate) fn dir(&self) -> Option<&Path> {
        self.dir.as_deref()
    }

    /// Where the models come from, for messages and reports: the directory, or
    /// `bundled:objects`.
    pub(crate) fn location(&self) -> PathBuf {
        self.dir
            .clone()
            .unwrap_or_else(|| PathBuf::from(format!("{}{BUNDLED_OBJECTS}", super::BUNDLED_PREFIX)))
    }

    /// The split that comes with the library: `split.json` at its root.
    pub(crate) fn default_split(&self) -> SplitFile {
        match &self.dir {
            Some(dir) => SplitFile::Path(dir.join("split.json")),
            None => SplitFile::Bundled,
        }
    }

    /// Names of all objects with a model.urdf, sorted.
    pub(crate) fn names(&self) -> Vec<String> {
        let Some(dir) = &self.dir else {
            return super::bundled_folders(BUNDLED_OBJECTS);
        };
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .into_iter()
            .flatten()
            .flatten()
            .filter(|e| e.path().join("model.urdf").is_file())
            .filter_map(|e| e.file_name().to_str().map(str::to_owned))
            .collect();
        names.sort();
        names
    }

    /// Loads one object by name.
    pub fn load(&self, name: &str) -> Result<ObjectModel, ObjectError> {
        let path = self.location().join(name).join("model.urdf");
        let unknown = || ObjectError::Unknown {
            name: name.to_owned(),
            library: self.dir.clone(),
            known: self.names(),
        };
        if name.is_empty() || name.contains(['/', '\\']) {
            return Err(unknown());
        }
        let file = match &self.dir {
            Some(_) if !path.is_file() => return Err(unknown()),
            Some(_) => UrdfFile::read(&path)?,
            None => {
                let text = super::bundled_text(&format!("{BUNDLED_OBJECTS}/{name}/model.urdf"))
                    .ok_or_else(unknown)?;
                UrdfFile::parse(text, &path)?
            }
        };
        object_from_urdf(name, &file)
    }

    /// Loads several objects, failing on the first bad one.
    pub fn load_all(&self, names: &[String]) -> Result<Vec<ObjectModel>, ObjectError> {
        names.iter().map(|n| self.load(n)).collect()
    }
}

/// Builds an object from a parsed URDF: every link's geometry is merged into one rigid body.
pub(crate) fn object_from_urdf(name: &str, file: &UrdfFile) -> Result<ObjectModel, ObjectError> {
    let invalid = |message: &str| ObjectError::Invalid {
        path: file.path.clone(),
        message: message.to_owned(),
    };
    let mut model = ObjectModel {
        name: name.to_owned(),
        mass: 0.0,
        friction: DEFAULT_FRICTION,
        collisions: Vec::new(),
        visuals: Vec::new(),
    };
    let mut friction = None;
    for index in 0..file.robot.links.len() {
        let link = file.link_geometry(index)?;
        model.mass += link.mass.unwrap_or(0.0);
        friction = friction.or(link.lateral_friction);
        model.collisions.extend(link.collisions);
        model.visuals.extend(link.visuals);
    }
    if file.robot.links.len() > 1 && !file.robot.joints.is_empty() {
        return Err(invalid(
            "objects must be a single link (articulated objects are not supported)",
        ));
    }
    if model.collisions.is_empty() {
        return Err(invalid("the object has no <collision> geometry"));
    }
    if model.mass <= 0.0 {
        return Err(invalid("the object needs a positive <inertial><mass>"));
    }
    model.friction = friction.unwrap_or(DEFAULT_FRICTION);
    Ok(model)
}

/// Which objects are for training and which for testing.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct Split {
    /// Objects seen in labelling and training.
    pub(crate) train: Vec<String>,
    /// Held-out objects.
    pub(crate) test: Vec<String>,
}

/// Where the split comes from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum SplitFile {
    /// The bundled objects' split.
    Bundled,
    /// A JSON file on disk.
    Path(PathBuf),
}

impl SplitFile {
    /// The file's path, or `bundled:objects/split.json`, for messages and reports.
    pub(crate) fn location(&self) -> PathBuf {
        match self {
            SplitFile::Path(path) => path.clone(),
            SplitFile::Bundled => PathBuf::from(format!(
                "{}{BUNDLED_OBJECTS}/split.json",
                super::BUNDLED_PREFIX
            )),
        }
    }

    /// Reads and checks the split.
    pub fn read(&self) -> Result<Split, ObjectError> {
        match self {
            SplitFile::Path(path) => Split::read(path),
            SplitFile::Bundled => {
                let path = self.location();
                let text = super::bundled_text(&format!("{BUNDLED_OBJECTS}/split.json"))
                    .ok_or_else(|| ObjectError::Split {
                        path: path.clone(),
                        message: "missing from the build".into(),
                    })?;
                Split::parse(text, &path)
            }
        }
    }
}

impl Split {
    /// Reads a split JSON file.
    pub(crate) fn read(path: &Path) -> Result<Self, ObjectError> {
        let text = std::fs::read_to_string(path).map_err(|e| ObjectError::Split {
            path: path.to_owned(),
            message: e.to_string(),
        })?;
        Self::parse(&text, path)
    }

    /// Parses split JSON; `path` names it in errors.
    pub(crate) fn parse(text: &str, path: &Path) -> Result<Self, ObjectError> {
        let err = |message: String| ObjectError::Split {
            path: path.to_owned(),
            message,
        };
        let split: Split = serde_json::from_str(text).map_err(|e| err(e.to_string()))?;
        if split.train.is_empty() {
            return Err(err("the train list is empty".into()));
        }
        let mut seen = std::collections::BTreeSet::new();
        for (list, name) in split
            .train
            .iter()
            .map(|n| ("train", n))
            .chain(split.test.iter().map(|n| ("test", n)))
        {
            if !seen.insert(name) {
                let both = split.train.contains(name) && split.test.contains(name);
                return Err(ObjectError::SplitObjects {
                    path: path.to_owned(),
                    message: if both {
                        format!("'{name}' is in both the train and the test list; keep it in one")
                    } else {
                        format!("'{name}' is listed twice in the {list} list; keep one")
                    },
                });
            }
        }
        Ok(split)
    }

    /// Checks that every object the split names is one the library has.
    pub(crate) fn check_objects(
        &self,
        path: &Path,
        library: &ObjectLibrary,
    ) -> Result<(), ObjectError> {
        let known = library.names();
        match self.all().into_iter().find(|n| !known.contains(n)) {
            None => Ok(()),
            Some(name) => Err(ObjectError::SplitObjects {
                path: path.to_owned(),
                message: format!(
                    "names '{name}', which is not an object{}; {}",
                    in_library(&library.dir),
                    known_list(&library.dir, &known)
                ),
            }),
        }
    }

    /// Every object, train first.
    pub fn all(&self) -> Vec<String> {
        self.train.iter().chain(&self.test).cloned().collect()
    }
}

#[cfg(test)]
mod fuzz {
    use std::path::Path;

    use proptest::prelude::*;

    use crate::data::fuzzing::{check, config, edits, mutate, text};

    const SPLIT: &str = include_str!("../../assets/objects/split.json");

    proptest! {
        #![proptest_config(config())]

        #[test]
        fn fuzz_json_split(edits in edits()) {
            let input = text(&mutate(SPLIT.as_bytes(), &edits));
            check(|| crate::assets::objects::Split::parse(&input, Path::new("split.json")))?;
        }
    }
}
