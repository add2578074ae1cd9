//! The one boundary with URDF files: turns urdf-rs links (plus the Bullet tags urdf-rs drops) into the crate's own geometry.
//!
//! Cylinders and capsules are converted from URDF's z-axis convention to the y-axis convention
//! shared by parry and the renderer. Meshes (OBJ, STL) are read here, so that a missing or broken
//! mesh is an error that names the file instead of a silently empty link.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use rapier3d::math::{Pose, Rotation, Vector};

use crate::vision::render::{Shape, TriMesh};

/// Colour of a visual that names no colour at all (a neutral light grey).
const DEFAULT_COLOR: [f32; 3] = [0.7, 0.7, 0.7];

/// One drawable piece of a link, in the link's frame.
#[derive(Debug, Clone)]
pub struct Visual {
    /// Geometry in the renderer's conventions.
    pub shape: Shape,
    /// Pose of the shape in the link frame.
    pub(crate) pose: Pose,
    /// Albedo in [0, 1].
    pub color: [f32; 3],
}

/// A collision primitive, in the link's frame, with parry's axis conventions (cylinders along y).
#[derive(Debug, Clone, PartialEq)]
pub enum CollisionShape {
    /// Box with half extents.
    Cuboid { half_extents: Vector },
    /// Sphere.
    Sphere { radius: f32 },
    /// Cylinder along local y.
    Cylinder { radius: f32, half_height: f32 },
    /// Capsule along local y (half height of the straight part).
    Capsule { radius: f32, half_height: f32 },
    /// The convex hull of these points (one convex piece of a mesh).
    ConvexHull { points: Vec<Vector> },
}

/// A collision primitive placed in the link frame.
#[derive(Debug, Clone)]
pub struct Collision {
    /// The shape.
    pub shape: CollisionShape,
    /// Its pose in the link frame.
    pub pose: Pose,
}

/// Everything the crate uses from one URDF link.
#[derive(Debug, Clone)]
pub struct LinkGeometry {
    /// Drawable pieces.
    pub(crate) visuals: Vec<Visual>,
    /// Collision pieces.
    pub collisions: Vec<Collision>,
    /// `<inertial><mass>`, if present and positive.
    pub(crate) mass: Option<f32>,
    /// Bullet's `<contact><lateral_friction value=…>`, if present.
    pub(crate) lateral_friction: Option<f32>,
}

/// Failures reading a URDF or the meshes it references.
#[derive(Debug, thiserror::Error)]
pub enum UrdfError {
    /// The URDF file could not be read.
    #[error("cannot read {path}: {source}")]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    /// The URDF text is not valid URDF.
    #[error("{path} is not a valid urdf: {message}")]
    Parse { path: PathBuf, message: String },
    /// A referenced mesh file does not exist.
    #[error("mesh {mesh} referenced by link '{link}' in {urdf} does not exist")]
    MissingMesh {
        urdf: PathBuf,
        link: String,
        mesh: PathBuf,
    },
    /// A referenced mesh exists but cannot be parsed or is empty.
    #[error("mesh {mesh} referenced by link '{link}' is unreadable: {message}")]
    BadMesh {
        link: String,
        mesh: PathBuf,
        message: String,
    },
    /// A value in the file is out of range.
    #[error("link '{link}' in {urdf}: {message}")]
    BadValue {
        urdf: PathBuf,
        link: String,
        message: String,
    },
}

/// A parsed URDF file with the raw text kept for the tags urdf-rs ignores.
#[derive(Debug, Clone)]
pub struct UrdfFile {
    /// Path it was read from.
    pub(crate) path: PathBuf,
    /// The urdf-rs model.
    pub(crate) robot: urdf_rs::Robot,
    /// Per link name, Bullet's lateral friction tag.
    frictions: Vec<(String, f32)>,
}

impl UrdfFile {
    /// Reads and parses a URDF file. Only this function touches the disk for the URDF itself.
    pub fn read(path: &Path) -> Result<Self, UrdfError> {
        let text = std::fs::read_to_string(path).map_err(|source| UrdfError::Read {
            path: path.to_owned(),
            source,
        })?;
        Self::parse(&text, path)
    }

    /// Parses URDF text; `path` is used for messages and to resolve relative mesh paths.
    pub(crate) fn parse(text: &str, path: &Path) -> Result<Self, UrdfError> {
        let parse_error = |message: String| UrdfError::Parse {
            path: path.to_owned(),
            message,
        };
        let robot = urdf_rs::read_from_string(text).map_err(|e| parse_error(e.to_string()))?;
        let frictions = bullet_lateral_frictions(text).map_err(parse_error)?;
        Ok(Self {
            path: path.to_owned(),
            robot,
            frictions,
        })
    }

    fn base_dir(&self) -> &Path {
        self.path.parent().unwrap_or_else(|| Path::new("."))
    }

    /// Converts one link's visuals, collisions, mass and friction, loading any meshes.
    pub fn link_geometry(&self, index: usize) -> Result<LinkGeometry, UrdfError> {
        let link = &self.robot.links[index];
        let mass = link.inertial.mass.value as f32;
        Ok(LinkGeometry {
            visuals: self.link_visuals(link)?,
            collisions: self.link_collisions(link)?,
            mass: (mass > 0.0).then_some(mass),
            lateral_friction: self
                .frictions
                .iter()
                .find(|(name, _)| *name == link.name)
                .map(|(_, mu)| *mu),
        })
    }

    /// A link's visuals, each mesh piece one, coloured by the material, else by the texture's
    /// mean, else by the mesh's own colour.
    fn link_visuals(&self, link: &urdf_rs::Link) -> Result<Vec<Visual>, UrdfError> {
        let mut visuals = Vec::new();
        for visual in &link.visual {
            let pose = urdf_pose(&visual.origin);
            let named_color = visual
                .material
                .as_ref()
                .and_then(|m| self.material_color(m));
            let texture = visual
                .material
                .as_ref()
                .and_then(|m| self.material_texture(m))
                .map(|t| self.base_dir().join(t));
            match &visual.geometry {
                urdf_rs::Geometry::Mesh { filename, scale } => {
                    let mesh = self.load_mesh(&link.name, filename, scale.as_ref())?;
                    let color = match named_color {
                        Some(c) if !is_white(c) => c,
                        _ => match texture.or(mesh.texture.clone()) {
                            Some(t) => {
                                mean_texture_color(&t).map_err(|message| UrdfError::BadMesh {
                                    link: link.name.clone(),
                                    mesh: t.clone(),
                                    message,
                                })?
                            }
                            None => named_color.or(mesh.color).unwrap_or(DEFAULT_COLOR),
                        },
                    };
                    for piece in mesh.pieces {
                        visuals.push(Visual {
                            shape: Shape::Mesh(Arc::new(piece)),
                            pose,
                            color,
                        });
                    }
                }
                geometry => {
                    let (shape, pose) = primitive(geometry, pose, &self.path, &link.name)?;
                    visuals.push(Visual {
                        shape: shape.to_render_shape(),
                        pose,
                        color: named_color.unwrap_or(DEFAULT_COLOR),
                    });
                }
            }
        }
        Ok(visuals)
    }

    /// A link's collision shapes, each mesh piece a convex hull.
    fn link_collisions(&self, link: &urdf_rs::Link) -> Result<Vec<Collision>, UrdfError> {
        let mut collisions = Vec::new();
        for collision in &link.collision {
            let pose = urdf_pose(&collision.origin);
            match &collision.geometry {
                urdf_rs::Geometry::Mesh { filename, scale } => {
                    let mesh = self.load_mesh(&link.name, filename, scale.as_ref())?;
                    for piece in mesh.pieces {
                        collisions.push(Collision {
                            shape: CollisionShape::ConvexHull {
                                points: piece.vertices,
                            },
                            pose,
                        });
                    }
                }
                geometry => {
                    let (shape, pose) = primitive(geometry, pose, &self.path, &link.name)?;
                    collisions.push(Collision { shape, pose });
                }
            }
        }
        Ok(collisions)
    }

    /// A material's colour, looking up robot-level materials referenced by name.
    fn material_color(&self, material: &urdf_rs::Material) -> Option<[f32; 3]> {
        let color = material.color.as_ref().or_else(|| {
            self.robot
                .materials
                .iter()
                .find(|m| m.name == material.name)
                .and_then(|m| m.color.as_ref())
        })?;
        let rgba = &color.rgba.0;
        Some([rgba[0] as f32, rgba[1] as f32, rgba[2] as f32])
    }

    fn material_texture(&self, material: &urdf_rs::Material) -> Option<String> {
        material
            .texture
            .as_ref()
            .or_else(|| {
                self.robot
                    .materials
                    .iter()
                    .find(|m| m.name == material.name)
                    .and_then(|m| m.texture.as_ref())
            })
            .map(|t| t.filename.clone())
    }

    fn resolve_mesh_path(&self, filename: &str) -> PathBuf {
        let relative = filename
            .strip_prefix("package://")
            .map(|rest| rest.split_once('/').map_or(rest, |(_, path)| path))
            .or_else(|| filename.strip_prefix("file://"))
            .unwrap_or(filename);
        let path = Path::new(relative);
        if path.is_absolute() {
            path.to_owned()
        } else {
            self.base_dir().join(path)
        }
    }

    fn load_mesh(
        &self,
        link: &str,
        filename: &str,
        scale: Option<&urdf_rs::Vec3>,
    ) -> Result<LoadedMesh, UrdfError> {
        let path = self.resolve_mesh_path(filename);
        if !path.is_file() {
            return Err(UrdfError::MissingMesh {
                urdf: self.path.clone(),
                link: link.to_owned(),
                mesh: path,
            });
        }
        let scale = scale.map_or(Vector::ONE, |s| {
            Vector::new(s.0[0] as f32, s.0[1] as f32, s.0[2] as f32)
        });
        load_mesh_file(&path, scale).map_err(|message| UrdfError::BadMesh {
            link: link.to_owned(),
            mesh: path,
            message,
        })
    }
}

/// A mesh file split into its pieces (OBJ objects/groups, or one piece for STL).
pub(crate) struct LoadedMesh {
    pieces: Vec<TriMesh>,
    color: Option<[f32; 3]>,
    texture: Option<PathBuf>,
}

fn load_mesh_file(path: &Path, scale: Vector) -> Result<LoadedMesh, String> {
    let bytes = std::fs::read(path).map_err(|e| e.to_string())?;
    load_mesh_bytes(bytes, path, scale)
}

/// Decodes an OBJ or STL mesh from its bytes; `path` gives the format (by extension) and
/// locates an OBJ's material library and textures.
pub(crate) fn load_mesh_bytes(
    mut bytes: Vec<u8>,
    path: &Path,
    scale: Vector,
) -> Result<LoadedMesh, String> {
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("obj"))
    {
        bytes = obj_objects_as_groups(&bytes);
    }
    // `path` still locates the .mtl and textures; mesh-loader reads those itself.
    let scene = mesh_loader::Loader::default()
        .merge_meshes(false)
        .load_from_slice(&bytes, path)
        .map_err(|e| e.to_string())?;
    let mut pieces = Vec::new();
    for mesh in &scene.meshes {
        if mesh.faces.is_empty() {
            continue;
        }
        let vertices = mesh
            .vertices
            .iter()
            .map(|v| Vector::new(v[0], v[1], v[2]) * scale)
            .collect::<Vec<_>>();
        if vertices.iter().any(|v| !v.is_finite()) {
            return Err("non-finite vertex coordinates".into());
        }
        let triangles = mesh.faces.clone();
        if triangles
            .iter()
            .flatten()
            .any(|&i| i as usize >= vertices.len())
        {
            return Err("face index out of range".into());
        }
        pieces.push(TriMesh {
            vertices,
            triangles,
        });
    }
    if pieces.is_empty() {
        return Err("no triangles".into());
    }
    let material = scene.materials.first();
    let color = material
        .and_then(|m| m.color.diffuse)
        .map(|c| [c[0], c[1], c[2]]);
    let texture = scene
        .materials
        .iter()
        .find_map(|m| m.texture.diffuse.clone())
        .map(|t| {
            if t.is_absolute() {
                t
            } else {
                path.parent().unwrap_or(Path::new(".")).join(t)
            }
        });
    Ok(LoadedMesh {
        pieces,
        color,
        texture,
    })
}

/// Makes every OBJ object (`o`) and group (`g`) its own mesh, keeping the active material.
///
/// mesh-loader 0.1 splits meshes at `g` lines but ignores `o` lines, so the convex pieces of a
/// V-HACD file (`o convex_0`, `o convex_1`, …) came back as one mesh, and their single hull
/// filled the gaps between the pieces. It also drops the active `usemtl` at every `g`, although
/// in OBJ a material stays in force until the next `usemtl`. So `o name` is rewritten as
/// `g name`, and the last `usemtl` line is repeated after each group line.
fn obj_objects_as_groups(bytes: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(bytes.len() + 256);
    let mut material: Option<&[u8]> = None;
    for line in bytes.split_inclusive(|&b| b == b'\n') {
        let is = |keyword: &[u8]| {
            line.starts_with(keyword) && matches!(line.get(keyword.len()), Some(b' ' | b'\t'))
        };
        let push_line = |out: &mut Vec<u8>, line: &[u8]| {
            out.extend_from_slice(line);
            if !line.ends_with(b"\n") {
                out.push(b'\n');
            }
        };
        if is(b"o") || is(b"g") {
            out.push(b'g');
            push_line(&mut out, &line[1..]);
            if let Some(usemtl) = material {
                push_line(&mut out, usemtl);
            }
        } else {
            if is(b"usemtl") {
                material = Some(line);
            }
            out.extend_from_slice(line);
        }
    }
    out
}

/// Mean colour of a texture image, the stand-in for textured YCB models.
fn mean_texture_color(path: &Path) -> Result<[f32; 3], String> {
    let image = image::open(path)
        .map_err(|e| format!("texture {}: {e}", path.display()))?
        .to_rgb8();
    let pixels = (image.width() as u64 * image.height() as u64).max(1) as f64;
    let mut sum = [0u64; 3];
    for p in image.pixels() {
        for (total, channel) in sum.iter_mut().zip(p.0) {
            *total += channel as u64;
        }
    }
    Ok(sum.map(|s| (s as f64 / pixels / 255.0) as f32))
}

fn is_white(c: [f32; 3]) -> bool {
    c.iter().all(|&v| v >= 0.99)
}

fn urdf_pose(origin: &urdf_rs::Pose) -> Pose {
    let [x, y, z] = origin.xyz.0;
    let [roll, pitch, yaw] = origin.rpy.0;
    Pose::from_parts(
        Vector::new(x as f32, y as f32, z as f32),
        rpy_rotation(roll, pitch, yaw),
    )
}

/// URDF's fixed-axis roll-pitch-yaw: R = Rz(yaw)·Ry(pitch)·Rx(roll).
pub(crate) fn rpy_rotation(roll: f64, pitch: f64, yaw: f64) -> Rotation {
    (Rotation::from_rotation_z(yaw as f32)
        * Rotation::from_rotation_y(pitch as f32)
        * Rotation::from_rotation_x(roll as f32))
    .normalize()
}

impl CollisionShape {
    /// The same geometry for the renderer (convex hulls are not drawable and become boxes of their bounds).
    pub(crate) fn to_render_shape(&self) -> Shape {
        match self {
            CollisionShape::Cuboid { half_extents } => Shape::Cuboid {
                half_extents: *half_extents,
            },
            CollisionShape::Sphere { radius } => Shape::Sphere { radius: *radius },
            CollisionShape::Cylinder {
                radius,
                half_height,
            } => Shape::Cylinder {
                radius: *radius,
                half_height: *half_height,
            },
            CollisionShape::Capsule {
                radius,
                half_height,
            } => Shape::Capsule {
                radius: *radius,
                half_height: *half_height,
            },
            CollisionShape::ConvexHull { points } => {
                let (lo, hi) = points.iter().fold(
                    (Vector::splat(f32::MAX), Vector::splat(f32::MIN)),
                    |(lo, hi), p| (lo.min(*p), hi.max(*p)),
                );
                Shape::Cuboid {
                    half_extents: (hi - lo) * 0.5,
                }
            }
        }
    }
}

/// Converts a URDF primitive; cylinders and capsules get a quarter turn about x (z axis → y axis).
fn primitive(
    geometry: &urdf_rs::Geometry,
    pose: Pose,
    urdf: &Path,
    link: &str,
) -> Result<(CollisionShape, Pose), UrdfError> {
    let bad = |message: String| UrdfError::BadValue {
        urdf: urdf.to_owned(),
        link: link.to_owned(),
        message,
    };
    let z_to_y = Pose::from_rotation(Rotation::from_rotation_x(std::f32::consts::FRAC_PI_2));
    let positive = |name: &str, v: f64| {
        if v > 0.0 && v.is_finite() {
            Ok(v as f32)
        } else {
            Err(bad(format!("{name} must be positive, got {v}")))
        }
    };
    Ok(match geometry {
        urdf_rs::Geometry::Box { size } => {
            let [x, y, z] = size.0;
            (
                CollisionShape::Cuboid {
                    half_extents: Vector::new(
                        positive("box size", x)? * 0.5,
                        positive("box size", y)? * 0.5,
                        positive("box size", z)? * 0.5,
                    ),
                },
                pose,
            )
        }
        urdf_rs::Geometry::Sphere { radius } => (
            CollisionShape::Sphere {
                radius: positive("sphere radius", *radius)?,
            },
            pose,
        ),
        urdf_rs::Geometry::Cylinder { radius, length } => (
            CollisionShape::Cylinder {
                radius: positive("cylinder radius", *radius)?,
                half_height: positive("cylinder length", *length)? * 0.5,
            },
            pose * z_to_y,
        ),
        urdf_rs::Geometry::Capsule { radius, length } => (
            CollisionShape::Capsule {
                radius: positive("capsule radius", *radius)?,
                half_height: positive("capsule length", *length)? * 0.5,
            },
            pose * z_to_y,
        ),
        urdf_rs::Geometry::Mesh { .. } => unreachable!("meshes are handled by the caller"),
    })
}

/// Finds `<link name=…><contact><lateral_friction value=…/>` tags, which urdf-rs does not model.
fn bullet_lateral_frictions(text: &str) -> Result<Vec<(String, f32)>, String> {
    let document = roxmltree::Document::parse(text).map_err(|e| e.to_string())?;
    let mut found = Vec::new();
    for link in document
        .descendants()
        .filter(|n| n.has_tag_name("link") && n.parent().is_some_and(|p| p.has_tag_name("robot")))
    {
        let Some(name) = link.attribute("name") else {
            continue;
        };
        let friction = link
            .children()
            .filter(|n| n.has_tag_name("contact"))
            .flat_map(|c| c.children())
            .find(|n| n.has_tag_name("lateral_friction"));
        if let Some(node) = friction {
            let raw = node.attribute("value").unwrap_or("");
            let value: f32 = raw.trim().parse().map_err(|_| {
                format!("link '{name}': lateral_friction value '{raw}' is not a number")
            })?;
            if !(value >= 0.0 && value.is_finite()) {
                return Err(format!(
                    "link '{name}': lateral_friction must be non-negative, got {value}"
                ));
            }
            found.push((name.to_owned(), value));
        }
    }
    Ok(found)
}

#[cfg(test)]
mod tests {
    use super::*;

    const URDF: &str = r#"<?xml version="1.0"?>
<robot name="Thing">
  <material name="shared_red"><color rgba="1 0 0 1"/></material>
  <link name="base_link">
    <contact><lateral_friction value="0.35"/></contact>
    <inertial><mass value="0.25"/><inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1e-4"/></inertial>
    <visual><geometry><cylinder radius="0.03" length="0.1"/></geometry><material name="shared_red"/></visual>
    <collision><origin xyz="0 0 0.01" rpy="0 0 0"/><geometry><cylinder radius="0.03" length="0.1"/></geometry></collision>
  </link>
</robot>"#;

    #[test]
    fn bullet_friction_mass_and_named_material_are_read() {
        let file = UrdfFile::parse(URDF, Path::new("/nowhere/model.urdf")).unwrap();
        let link = file.link_geometry(0).unwrap();
        assert_eq!(link.lateral_friction, Some(0.35));
        assert_eq!(link.mass, Some(0.25));
        assert_eq!(link.visuals[0].color, [1.0, 0.0, 0.0]);
    }

    #[test]
    fn urdf_cylinders_stand_along_z_after_conversion() {
        let file = UrdfFile::parse(URDF, Path::new("/nowhere/model.urdf")).unwrap();
        let link = file.link_geometry(0).unwrap();
        let c = &link.collisions[0];
        assert_eq!(
            c.shape,
            CollisionShape::Cylinder {
                radius: 0.03,
                half_height: 0.05
            }
        );
        // The cylinder's own y axis must map to the link's z axis.
        let axis = c.pose.rotation * Vector::Y;
        assert!((axis - Vector::Z).length() < 1e-6, "axis {axis:?}");
        assert!((c.pose.translation - Vector::new(0.0, 0.0, 0.01)).length() < 1e-6);
    }

    #[test]
    fn rpy_matches_urdf_fixed_axis_convention() {
        // yaw = 90°: x axis → y axis.
        let r = rpy_rotation(0.0, 0.0, std::f64::consts::FRAC_PI_2);
        assert!((r * Vector::X - Vector::Y).length() < 1e-6);
        // roll then yaw: the z axis after roll 90° is −y, then yaw 90° takes −y to +x.
        let r = rpy_rotation(
            std::f64::consts::FRAC_PI_2,
            0.0,
            std::f64::consts::FRAC_PI_2,
        );
        assert!(
            (r * Vector::Z - Vector::X).length() < 1e-6,
            "{:?}",
            r * Vector::Z
        );
    }

    #[test]
    fn bad_friction_value_is_an_error_naming_the_link() {
        let text = URDF.replace("0.35", "slippery");
        let err = UrdfFile::parse(&text, Path::new("m.urdf")).unwrap_err();
        assert!(err.to_string().contains("base_link"), "{err}");
        assert!(err.to_string().contains("slippery"), "{err}");
    }

    #[test]
    fn missing_mesh_is_an_error_naming_the_file() {
        let text = URDF.replace(
            r#"<cylinder radius="0.03" length="0.1"/></geometry></collision>"#,
            r#"<mesh filename="collision_vhacd.obj"/></geometry></collision>"#,
        );
        let file = UrdfFile::parse(&text, Path::new("/nowhere/Thing/model.urdf")).unwrap();
        let err = file.link_geometry(0).unwrap_err();
        assert!(matches!(err, UrdfError::MissingMesh { .. }));
        assert!(err.to_string().contains("collision_vhacd.obj"), "{err}");
    }
}

#[cfg(test)]
mod fuzz {
    use std::path::Path;

    use proptest::prelude::*;
    use rapier3d::math::Vector;

    use crate::data::fuzzing::{check, config, edits, mutate, text};

    const HAMMER_URDF: &str = include_str!("../../assets/objects/YcbHammer/model.urdf");
    const CUBE_OBJ: &str =
        "o piece\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n";

    fn binary_stl() -> Vec<u8> {
        let mut bytes = vec![0u8; 80];
        bytes.extend(2u32.to_le_bytes());
        for triangle in [[[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]; 2] {
            bytes.extend([0.0f32; 3].iter().flat_map(|c| c.to_le_bytes()));
            for vertex in triangle {
                bytes.extend(vertex.iter().flat_map(|c| c.to_le_bytes()));
            }
            bytes.extend(0u16.to_le_bytes());
        }
        bytes
    }

    proptest! {
        #![proptest_config(config())]

        #[test]
        fn fuzz_urdf(edits in edits()) {
            let input = text(&mutate(HAMMER_URDF.as_bytes(), &edits));
            check(|| {
                let file = crate::assets::urdf::UrdfFile::parse(&input, Path::new("model.urdf"))?;
                crate::assets::objects::object_from_urdf("Fuzzed", &file)
                    .map_err(|e| anyhow::anyhow!("{e}"))
            })?;
        }

        #[test]
        fn fuzz_obj(edits in edits()) {
            let input = mutate(CUBE_OBJ.as_bytes(), &edits);
            check(|| {
                crate::assets::urdf::load_mesh_bytes(input, Path::new("/nonexistent/piece.obj"), Vector::ONE)
            })?;
        }

        #[test]
        fn fuzz_stl(edits in edits()) {
            let input = mutate(&binary_stl(), &edits);
            check(|| {
                crate::assets::urdf::load_mesh_bytes(input, Path::new("/nonexistent/piece.stl"), Vector::ONE)
            })?;
        }
    }
}
