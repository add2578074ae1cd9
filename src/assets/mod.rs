//! Model files: the bundled robot and objects (embedded in the binary), the URDF boundary and
//! the object catalogue.
//!
//! The one place that reads urdf-rs, Bullet's `<contact>` tag and mesh files, and converts
//! them into the crate's own types. It may use the pure core only. The bundled models are
//! compiled in, so an installed binary runs from any directory; `--objects-dir` points the
//! catalogue at a directory on disk instead.

pub mod objects;
#[cfg(test)]
mod true_size;
pub mod urdf;

use include_dir::{include_dir, Dir};

/// The repository's default object models, compiled in. Only this folder: assets/ycb-meshes (the
/// reference's meshes, LGPL) stays a directory that `--objects-dir` reads, outside the binary.
static BUNDLED: Dir<'static> = include_dir!("$CARGO_MANIFEST_DIR/assets/objects");

/// How bundled files are named in messages and reports: they have no path on disk.
pub(crate) const BUNDLED_PREFIX: &str = "bundled:";

/// A bundled text file by its path under assets/, e.g. `objects/split.json`.
pub(crate) fn bundled_text(path: &str) -> Option<&'static str> {
    let inside = path.strip_prefix("objects/")?;
    BUNDLED.get_file(inside)?.contents_utf8()
}

/// The folder names directly under a bundled folder, sorted.
pub(crate) fn bundled_folders(path: &str) -> Vec<String> {
    let dir = match path {
        "objects" => &BUNDLED,
        _ => match path
            .strip_prefix("objects/")
            .and_then(|p| BUNDLED.get_dir(p))
        {
            Some(dir) => dir,
            None => return Vec::new(),
        },
    };
    let mut names: Vec<String> = dir
        .dirs()
        .filter_map(|d| d.path().file_name()?.to_str().map(str::to_owned))
        .collect();
    names.sort();
    names
}

/// The UR5's URDF (compiled in; it names no mesh files).
pub(crate) const UR5_URDF: &str = include_str!("../../assets/ur5/ur5.urdf");

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_robot_and_all_fifteen_objects_are_compiled_in() {
        assert!(UR5_URDF.contains("tool0"));
        let objects = bundled_folders("objects");
        assert_eq!(objects.len(), 15, "{objects:?}");
        assert!(bundled_text("objects/split.json").is_some());
        assert!(bundled_text("objects/YcbHammer/model.urdf").is_some());
    }
}
