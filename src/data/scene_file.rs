//! Scene files: a fixed arrangement of objects in bin 1, as graspmap's own JSON
//! (`graspmap.scene/1`) or as one of VPG's test cases (docs/scenes.md).
//!
//! Poses are in bin 1's frame: its origin is the middle of the bin's floor top, its axes are the
//! world's. Reading checks every number and pose, so that a bad file fails before any physics,
//! naming the file, the line or object, and the fix; whether the names exist and whether the
//! objects overlap is for the caller that holds the object library and the simulator.

use std::path::{Path, PathBuf};

use rapier3d::math::{Pose, Rotation, Vector};
use serde::{Deserialize, Serialize};

use crate::grasp::tote::{INNER_HALF, WALL_TOP};

/// The schema name graspmap's scene files carry.
pub const SCENE_SCHEMA: &str = "graspmap.scene/1";

/// VPG's workspace limits (m, its world frame): x, y and the table at z = 0. Objects listed
/// outside it are parked there by VPG's simulator and are not part of the case.
const VPG_WORKSPACE: [[f64; 2]; 2] = [[-0.724, -0.276], [-0.224, 0.224]];
/// The lowest and highest centre height (m) that VPG's cases put an object inside the
/// workspace at; parked objects lie far below.
const VPG_HEIGHT: [f64; 2] = [-0.05, 0.3];
/// How far below the floor's top an object's listed centre may lie (m): a flat shape lying on
/// the floor has its centre only millimetres above it, and rounding may put it lower.
const BELOW_FLOOR: f32 = 0.01;
/// How far a quaternion's length may be from 1 before it counts as a mistake, not rounding.
const UNIT_TOLERANCE: f32 = 1e-3;

/// One object of a scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlacedObject {
    /// The object's name in the objects directory.
    pub name: String,
    /// Its frame's origin in bin 1's frame (m).
    pub position: [f32; 3],
    /// Its orientation, a unit quaternion x, y, z, w.
    pub orientation: [f32; 4],
    /// Its colour (RGB in [0, 1]), replacing the model's own; absent keeps the model's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub color: Option<[f32; 3]>,
}

impl PlacedObject {
    /// The object's pose in the world, bin 1's floor top being at `floor` (world x, y, z).
    pub fn world_pose(&self, floor: Vector) -> Pose {
        let [x, y, z] = self.position;
        let [qx, qy, qz, qw] = self.orientation;
        Pose::from_parts(
            floor + Vector::new(x, y, z),
            Rotation::from_xyzw(qx, qy, qz, qw).normalize(),
        )
    }
}

/// Which format a scene file was read from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SceneFormat {
    /// graspmap's JSON.
    Graspmap,
    /// VPG's test-case text.
    Vpg,
}

/// A scene file, read and checked.
#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    /// Its name in reports: the file's stem.
    pub name: String,
    /// Where it was read from.
    pub path: PathBuf,
    /// Its format.
    pub format: SceneFormat,
    /// Its objects, in the file's order.
    pub objects: Vec<PlacedObject>,
}

/// graspmap's scene file as written.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneJson {
    schema: String,
    objects: Vec<PlacedObject>,
}

/// Why a scene file was refused.
#[derive(Debug, thiserror::Error)]
#[error("scene file {}{}: {message}", path.display(), line.map_or_else(String::new, |l| format!(":{l}")))]
pub struct SceneError {
    /// The file.
    pub path: PathBuf,
    /// The 1-based line, for VPG's text.
    pub line: Option<usize>,
    /// What is wrong and how to fix it.
    pub message: String,
}

impl Scene {
    /// Reads a scene file: `.json` as graspmap's, anything else as VPG's text.
    pub fn read(path: &Path) -> Result<Self, SceneError> {
        let error = |message: String| SceneError {
            path: path.to_owned(),
            line: None,
            message,
        };
        let bytes = std::fs::read(path).map_err(|e| error(format!("cannot be read ({e})")))?;
        let text = String::from_utf8(bytes)
            .map_err(|_| error("is not UTF-8 text (a JSON or VPG test-case file)".into()))?;
        let is_json = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("json"));
        match is_json {
            true => Self::parse_json(&text, path),
            false => Self::parse_vpg(&text, path),
        }
    }

    /// Every scene file that `paths` name: files as they are, and in a directory its `.json`
    /// and `.txt` files, sorted by name.
    pub fn read_all(paths: &[PathBuf]) -> Result<Vec<Self>, SceneError> {
        let mut scenes = Vec::new();
        for path in paths {
            if path.is_dir() {
                let error = |message: String| SceneError {
                    path: path.clone(),
                    line: None,
                    message,
                };
                let mut files: Vec<PathBuf> = std::fs::read_dir(path)
                    .map_err(|e| error(format!("cannot be listed ({e})")))?
                    .filter_map(|entry| entry.ok().map(|e| e.path()))
                    .filter(|p| {
                        p.is_file() && p.extension().is_some_and(|e| e == "json" || e == "txt")
                    })
                    .collect();
                files.sort();
                if files.is_empty() {
                    return Err(error(
                        "is a directory without scene files (.json or VPG's .txt)".into(),
                    ));
                }
                for file in files {
                    scenes.push(Self::read(&file)?);
                }
            } else {
                scenes.push(Self::read(path)?);
            }
        }
        let mut names: Vec<&str> = scenes.iter().map(|s| s.name.as_str()).collect();
        names.sort_unstable();
        if let Some(twice) = names.windows(2).find(|w| w[0] == w[1]) {
            let second = scenes.iter().rev().find(|s| s.name == twice[0]);
            return Err(SceneError {
                path: second.map_or_else(PathBuf::new, |s| s.path.clone()),
                line: None,
                message: format!(
                    "another scene file is also named '{}'; reports name scenes by file stem, so rename one",
                    twice[0]
                ),
            });
        }
        Ok(scenes)
    }

    /// Parses graspmap's JSON; `path` names the file in errors.
    pub fn parse_json(text: &str, path: &Path) -> Result<Self, SceneError> {
        let error = |message: String| SceneError {
            path: path.to_owned(),
            line: None,
            message,
        };
        let file: SceneJson = serde_json::from_str(text).map_err(|e| {
            error(format!(
                "{e} (expected {{\"schema\": \"{SCENE_SCHEMA}\", \"objects\": [{{\"name\", \"position\", \"orientation\", \"color\"?}}]}})"
            ))
        })?;
        if file.schema != SCENE_SCHEMA {
            return Err(error(format!(
                "schema '{}', expected '{SCENE_SCHEMA}'",
                file.schema
            )));
        }
        let scene = Self {
            name: stem(path),
            path: path.to_owned(),
            format: SceneFormat::Graspmap,
            objects: file.objects,
        };
        for (i, object) in scene.objects.iter().enumerate() {
            check_object(object)
                .map_err(|why| error(format!("object {} ({}): {why}", i + 1, object.name)))?;
        }
        scene.check_not_empty()?;
        Ok(scene)
    }

    /// Parses one of VPG's test cases: a line per object, `mesh r g b x y z α β γ` (colour in
    /// [0, 1], position in metres in VPG's world frame, V-REP Euler angles in radians). Mesh
    /// `N.obj` places object `BlockN`; the workspace's centre goes to bin 1's centre; objects
    /// outside the workspace are left out.
    pub fn parse_vpg(text: &str, path: &Path) -> Result<Self, SceneError> {
        let mut objects = Vec::new();
        for (i, line) in text.lines().enumerate() {
            let error = |message: String| SceneError {
                path: path.to_owned(),
                line: Some(i + 1),
                message,
            };
            let fields: Vec<&str> = line.split_whitespace().collect();
            if fields.is_empty() {
                continue;
            }
            if fields.len() != 10 {
                return Err(error(format!(
                    "{} fields, expected 10 (mesh r g b x y z alpha beta gamma)",
                    fields.len()
                )));
            }
            let name = vpg_block(fields[0]).ok_or_else(|| {
                error(format!(
                    "'{}' is not one of VPG's block meshes (N.obj, e.g. 4.obj)",
                    fields[0]
                ))
            })?;
            let mut numbers = [0f64; 9];
            for (k, field) in fields[1..].iter().enumerate() {
                numbers[k] = field
                    .parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| error(format!("'{field}' is not a finite number")))?;
            }
            let [r, g, b, x, y, z, alpha, beta, gamma] = numbers;
            let inside = (VPG_WORKSPACE[0][0]..=VPG_WORKSPACE[0][1]).contains(&x)
                && (VPG_WORKSPACE[1][0]..=VPG_WORKSPACE[1][1]).contains(&y)
                && (VPG_HEIGHT[0]..=VPG_HEIGHT[1]).contains(&z);
            if !inside {
                continue;
            }
            let centre = [
                (VPG_WORKSPACE[0][0] + VPG_WORKSPACE[0][1]) / 2.0,
                (VPG_WORKSPACE[1][0] + VPG_WORKSPACE[1][1]) / 2.0,
            ];
            // V-REP's Euler angles: R = Rx(α)·Ry(β)·Rz(γ).
            let rotation = Rotation::from_rotation_x(alpha as f32)
                * Rotation::from_rotation_y(beta as f32)
                * Rotation::from_rotation_z(gamma as f32);
            let object = PlacedObject {
                name,
                position: [(x - centre[0]) as f32, (y - centre[1]) as f32, z as f32],
                orientation: rotation.normalize().to_array(),
                color: Some([r as f32, g as f32, b as f32]),
            };
            check_object(&object).map_err(error)?;
            objects.push(object);
        }
        let scene = Self {
            name: stem(path),
            path: path.to_owned(),
            format: SceneFormat::Vpg,
            objects,
        };
        scene.check_not_empty()?;
        Ok(scene)
    }

    /// The scene as graspmap's JSON.
    pub fn to_json(&self) -> String {
        let file = SceneJson {
            schema: SCENE_SCHEMA.to_owned(),
            objects: self.objects.clone(),
        };
        serde_json::to_string_pretty(&file).expect("a scene serialises") + "\n"
    }

    fn check_not_empty(&self) -> Result<(), SceneError> {
        if self.objects.is_empty() {
            return Err(SceneError {
                path: self.path.clone(),
                line: None,
                message: match self.format {
                    SceneFormat::Graspmap => "lists no objects".into(),
                    SceneFormat::Vpg => format!(
                        "lists no object inside VPG's workspace (x {:?}, y {:?} m)",
                        VPG_WORKSPACE[0], VPG_WORKSPACE[1]
                    ),
                },
            });
        }
        Ok(())
    }
}

/// `N.obj` → `BlockN`.
fn vpg_block(mesh: &str) -> Option<String> {
    let number = mesh.strip_suffix(".obj")?;
    (!number.is_empty() && number.chars().all(|c| c.is_ascii_digit()))
        .then(|| format!("Block{number}"))
}

fn stem(path: &Path) -> String {
    path.file_stem()
        .map_or_else(|| "scene".to_owned(), |s| s.to_string_lossy().into_owned())
}

/// Checks one object's numbers: finite, a unit quaternion, a colour in [0, 1], and a position
/// inside bin 1.
fn check_object(object: &PlacedObject) -> Result<(), String> {
    let all = object
        .position
        .iter()
        .chain(&object.orientation)
        .chain(object.color.iter().flatten());
    if all.clone().any(|v| !v.is_finite()) {
        return Err("a number is not finite".into());
    }
    let length = object.orientation.iter().map(|q| q * q).sum::<f32>().sqrt();
    if (length - 1.0).abs() > UNIT_TOLERANCE {
        return Err(format!(
            "orientation {:?} is not a unit quaternion (x, y, z, w; its length is {length:.4})",
            object.orientation
        ));
    }
    if let Some(color) = object.color {
        if color.iter().any(|c| !(0.0..=1.0).contains(c)) {
            return Err(format!("color {color:?} is outside [0, 1]"));
        }
    }
    let [x, y, z] = object.position;
    let height = WALL_TOP - crate::grasp::tote::FLOOR_TOP;
    if x.abs() > INNER_HALF[0] || y.abs() > INNER_HALF[1] || !(-BELOW_FLOOR..=height).contains(&z) {
        return Err(format!(
            "position ({x:.3}, {y:.3}, {z:.3}) m is outside bin 1 (|x| ≤ {:.2}, |y| ≤ {:.2}, z from {:.2} to {height:.2} above the floor's middle)",
            INNER_HALF[0], INNER_HALF[1], -BELOW_FLOOR
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const CASE: &str = "\
4.obj 0.35 0.63 0.31 -0.64 0.123 0.026 -1.5746 -1.0274 3.1371
6.obj 0.69 0.48 0.63 -0.69 -0.32 -726.58 -2.5 -0.7 0.1
0.obj 0.31 0.47 0.65 -0.864 -0.199 0.025 -1.57 -0.05 -1.56
";

    #[test]
    fn vpg_cases_map_the_workspace_centre_to_the_bin_and_leave_parked_objects_out() {
        let scene = Scene::parse_vpg(CASE, Path::new("test-10-obj-00.txt")).unwrap();
        assert_eq!(scene.name, "test-10-obj-00");
        assert_eq!(scene.objects.len(), 1);
        let cube = &scene.objects[0];
        assert_eq!(cube.name, "Block4");
        assert!((cube.position[0] - (-0.14)).abs() < 1e-5, "{cube:?}");
        assert!((cube.position[1] - 0.123).abs() < 1e-6);
        assert_eq!(cube.color, Some([0.35, 0.63, 0.31]));
    }

    #[test]
    fn vpg_euler_angles_compose_as_rx_ry_rz() {
        // Rx(π/2)·Rz(π/2) takes x to z: z first turns x into y, then x turns y into z.
        let text = "4.obj 1 1 1 -0.5 0 0.025 1.5707963 0 1.5707963\n";
        let scene = Scene::parse_vpg(text, Path::new("c.txt")).unwrap();
        let pose = scene.objects[0].world_pose(Vector::ZERO);
        let x = pose.rotation * Vector::X;
        assert!((x - Vector::Z).length() < 1e-5, "{x:?}");
    }

    #[test]
    fn bad_vpg_lines_name_the_line_and_the_fix() {
        for (text, expected) in [
            (
                "4.obj 1 1 1 -0.5 0 0.02 0 0\n",
                "c.txt:1: 9 fields, expected 10",
            ),
            (
                "\ncube 1 1 1 -0.5 0 0.02 0 0 0\n",
                "c.txt:2: 'cube' is not one of VPG's block meshes",
            ),
            (
                "4.obj 1 1 1 -0.5 NaN 0.02 0 0 0\n",
                "c.txt:1: 'NaN' is not a finite number",
            ),
            (
                "4.obj 1 2 1 -0.5 0 0.02 0 0 0\n",
                "c.txt:1: color [1.0, 2.0, 1.0] is outside [0, 1]",
            ),
            (
                "4.obj 1 1 1 -0.9 0 -700 0 0 0\n",
                "c.txt: lists no object inside VPG's workspace",
            ),
        ] {
            let error = Scene::parse_vpg(text, Path::new("c.txt"))
                .unwrap_err()
                .to_string();
            assert!(
                error.starts_with(&format!("scene file {expected}")),
                "{error}"
            );
        }
    }

    #[test]
    fn json_scenes_round_trip_and_refuse_poses_outside_the_bin() {
        let scene = Scene::parse_vpg(CASE, Path::new("a.txt")).unwrap();
        let back = Scene::parse_json(&scene.to_json(), Path::new("a.json")).unwrap();
        assert_eq!(back.objects, scene.objects);
        let outside = scene.to_json().replace("-0.14", "-0.94");
        let error = Scene::parse_json(&outside, Path::new("a.json"))
            .unwrap_err()
            .to_string();
        assert!(
            error.starts_with("scene file a.json: object 1 (Block4): position (-0.940"),
            "{error}"
        );
        let unknown_field = scene.to_json().replace("\"color\"", "\"colour\"");
        assert!(Scene::parse_json(&unknown_field, Path::new("a.json")).is_err());
        let not_unit = r#"{"schema": "graspmap.scene/1", "objects": [{"name": "A", "position": [0, 0, 0.02], "orientation": [0, 0, 0, 2]}]}"#;
        let error = Scene::parse_json(not_unit, Path::new("a.json"))
            .unwrap_err()
            .to_string();
        assert!(error.contains("is not a unit quaternion"), "{error}");
    }
}
