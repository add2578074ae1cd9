//! Object models and the train/test split: bundled primitive compounds or imported mesh URDFs, resolved by name.

use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::urdf::{Collision, UrdfError, UrdfFile, Visual};

/// Friction used when a URDF has no Bullet `<contact>` tag (Bullet's own default).
pub const DEFAULT_FRICTION: f32 = 0.5;

/// A graspable object: one rigid body with compound collision geometry.
#[derive(Debug, Clone)]
pub struct ObjectModel {
    /// Name (the directory name, e.g. `YcbMustardBottle`).
    pub name: String,
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
    #[error("unknown object '{name}': no {path}; known objects: {known}")]
    Unknown {
        name: String,
        path: PathBuf,
        known: String,
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
}

/// A directory of `<Name>/model.urdf` object models.
#[derive(Debug, Clone)]
pub struct ObjectLibrary {
    dir: PathBuf,
}

impl ObjectLibrary {
    /// A library rooted at `dir`.
    pub fn new(dir: impl Into<PathBuf>) -> Self {
        Self { dir: dir.into() }
    }

    /// The library's directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Names of all objects with a model.urdf, sorted.
    pub fn names(&self) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(&self.dir)
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
        let path = self.dir.join(name).join("model.urdf");
        if name.is_empty() || name.contains(['/', '\\']) || !path.is_file() {
            return Err(ObjectError::Unknown {
                name: name.to_owned(),
                path,
                known: self.names().join(", "),
            });
        }
        let file = UrdfFile::read(&path)?;
        object_from_urdf(name, &file)
    }

    /// Loads several objects, failing on the first bad one.
    pub fn load_all(&self, names: &[String]) -> Result<Vec<ObjectModel>, ObjectError> {
        names.iter().map(|n| self.load(n)).collect()
    }
}

/// Builds an object from a parsed URDF: every link's geometry is merged into one rigid body.
pub fn object_from_urdf(name: &str, file: &UrdfFile) -> Result<ObjectModel, ObjectError> {
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
    pub train: Vec<String>,
    /// Held-out objects.
    pub test: Vec<String>,
}

impl Split {
    /// Reads a split JSON file.
    pub fn read(path: &Path) -> Result<Self, ObjectError> {
        let err = |message: String| ObjectError::Split {
            path: path.to_owned(),
            message,
        };
        let text = std::fs::read_to_string(path).map_err(|e| err(e.to_string()))?;
        let split: Split = serde_json::from_str(&text).map_err(|e| err(e.to_string()))?;
        if split.train.is_empty() {
            return Err(err("the train list is empty".into()));
        }
        Ok(split)
    }

    /// Every object, train first.
    pub fn all(&self) -> Vec<String> {
        self.train.iter().chain(&self.test).cloned().collect()
    }
}
