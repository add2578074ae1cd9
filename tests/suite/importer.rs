//! Integration tests of the mesh/URDF object importer (meshes, convex pieces, scale, Bullet friction, texture colours), on fixtures written at test time.
//!
//! Every fixture (URDF, OBJ, MTL, STL, PNG) is generated into a temporary directory by the
//! helpers below, so no binary files are committed and each test states exactly what it feeds
//! the importer.

use std::path::{Path, PathBuf};

use graspmap::assets::objects::{
    ObjectError, ObjectLibrary, ObjectModel, SplitFile, DEFAULT_FRICTION,
};
use graspmap::assets::urdf::{CollisionShape, UrdfError, UrdfFile};
use graspmap::vision::render::Shape;
use rapier3d::math::Vector;

// ---------------------------------------------------------------------------------------------
// Fixture helpers

/// Writes `contents` to `dir/name` (creating parent directories) and returns the path.
fn write(dir: &Path, name: &str, contents: impl AsRef<[u8]>) -> PathBuf {
    let path = dir.join(name);
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    std::fs::write(&path, contents).unwrap();
    path
}

/// OBJ text of an axis-aligned box (8 `v` lines, 6 quad faces), numbered from vertex `first` (1-based).
///
/// OBJ indices are global to the file, so a second box in the same file starts at `first = 9`.
fn box_obj(center: [f32; 3], half: [f32; 3], first: usize) -> String {
    let mut text = String::new();
    for i in 0..8 {
        let sign = |bit: usize| if i & bit == 0 { -1.0 } else { 1.0 };
        text += &format!(
            "v {} {} {}\n",
            center[0] + sign(1) * half[0],
            center[1] + sign(2) * half[1],
            center[2] + sign(4) * half[2]
        );
    }
    // Corner index bits: 1 = +x, 2 = +y, 4 = +z.
    for quad in [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ] {
        let [a, b, c, d] = quad.map(|k| k + first);
        text += &format!("f {a} {b} {c} {d}\n");
    }
    text
}

/// A single-link URDF named `name` with `mass`, an optional Bullet friction tag and `body` (visual/collision XML).
fn urdf(name: &str, mass: f32, friction: Option<f32>, body: &str) -> String {
    let contact = friction.map_or(String::new(), |mu| {
        format!("<contact><lateral_friction value=\"{mu}\"/></contact>")
    });
    format!(
        r#"<?xml version="1.0"?>
<robot name="{name}">
  <link name="base_link">
    {contact}
    <inertial>
      <origin xyz="0 0 0" rpy="0 0 0"/>
      <mass value="{mass}"/>
      <inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1e-4"/>
    </inertial>
    {body}
  </link>
</robot>
"#
    )
}

/// `<collision>` with a mesh, optional `scale` attribute text and origin.
fn collision_mesh(file: &str, scale: Option<&str>, xyz: &str) -> String {
    let scale = scale.map_or(String::new(), |s| format!(" scale=\"{s}\""));
    format!(
        r#"<collision><origin xyz="{xyz}" rpy="0 0 0"/><geometry><mesh filename="{file}"{scale}/></geometry></collision>"#
    )
}

/// `<visual>` with a mesh and optional `<material>` XML.
fn visual_mesh(file: &str, material: &str) -> String {
    format!(
        r#"<visual><origin xyz="0 0 0" rpy="0 0 0"/><geometry><mesh filename="{file}"/></geometry>{material}</visual>"#
    )
}

/// Writes `<dir>/<name>/model.urdf` (the object-library layout) and returns the object directory.
fn write_object(dir: &Path, name: &str, urdf_text: &str) -> PathBuf {
    let object_dir = dir.join(name);
    write(&object_dir, "model.urdf", urdf_text);
    object_dir
}

/// Writes an RGB PNG of size `w`×`h` whose pixel (x, y) is `color(x, y)`.
fn write_png(path: &Path, w: u32, h: u32, color: impl Fn(u32, u32) -> [u8; 3]) {
    image::RgbImage::from_fn(w, h, |x, y| image::Rgb(color(x, y)))
        .save(path)
        .unwrap();
}

/// A 4×4 texture, left half pure red and right half pure blue: its mean colour is (0.5, 0, 0.5).
fn write_red_blue_png(path: &Path) {
    write_png(
        path,
        4,
        4,
        |x, _| if x < 2 { [255, 0, 0] } else { [0, 0, 255] },
    );
}

/// The four corners of the test tetrahedron (a right-angled corner at the origin).
const TETRA: [[f32; 3]; 4] = [
    [0.0, 0.0, 0.0],
    [0.05, 0.0, 0.0],
    [0.0, 0.04, 0.0],
    [0.0, 0.0, 0.03],
];
const TETRA_FACES: [[usize; 3]; 4] = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];

/// Binary STL: 80-byte header, triangle count, then per triangle normal, 3 vertices and a u16.
fn binary_stl(triangles: &[[[f32; 3]; 3]]) -> Vec<u8> {
    let mut bytes = vec![0u8; 80];
    bytes.extend((triangles.len() as u32).to_le_bytes());
    for tri in triangles {
        for value in [0.0f32; 3].iter().chain(tri.iter().flatten()) {
            bytes.extend(value.to_le_bytes());
        }
        bytes.extend(0u16.to_le_bytes());
    }
    bytes
}

/// ASCII STL of the same triangles.
fn ascii_stl(triangles: &[[[f32; 3]; 3]]) -> String {
    let mut text = String::from("solid tetra\n");
    for tri in triangles {
        text += "  facet normal 0 0 0\n    outer loop\n";
        for v in tri {
            text += &format!("      vertex {} {} {}\n", v[0], v[1], v[2]);
        }
        text += "    endloop\n  endfacet\n";
    }
    text + "endsolid tetra\n"
}

fn tetra_triangles() -> Vec<[[f32; 3]; 3]> {
    TETRA_FACES.iter().map(|f| f.map(|i| TETRA[i])).collect()
}

// ---------------------------------------------------------------------------------------------
// Assertion helpers

/// Axis-aligned bounds of a point set.
fn bounds(points: &[Vector]) -> (Vector, Vector) {
    assert!(!points.is_empty(), "no points");
    points.iter().fold(
        (Vector::splat(f32::MAX), Vector::splat(f32::MIN)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    )
}

fn assert_close(actual: Vector, expected: [f32; 3], what: &str) {
    let expected = Vector::from_array(expected);
    assert!(
        (actual - expected).abs().max_element() < 1e-5,
        "{what}: got {actual:?}, expected {expected:?}"
    );
}

fn assert_color(actual: [f32; 3], expected: [f32; 3], what: &str) {
    assert!(
        actual
            .iter()
            .zip(expected)
            .all(|(a, e)| (a - e).abs() < 1e-3),
        "{what}: got {actual:?}, expected {expected:?}"
    );
}

/// The points of a convex-hull collision piece (panics on any other shape).
fn hull_points(shape: &CollisionShape) -> &[Vector] {
    match shape {
        CollisionShape::ConvexHull { points } => points,
        other => panic!("expected a ConvexHull, got {other:?}"),
    }
}

/// Loads the one object `name` from the library rooted at `dir`.
fn load(dir: &Path, name: &str) -> Result<ObjectModel, ObjectError> {
    ObjectLibrary::new(dir).load(name)
}

// ---------------------------------------------------------------------------------------------
// Collision geometry

/// V-HACD writes each convex piece as an `o` object; `g` groups are the other common spelling.
/// Either way every piece must be its own convex hull, or two separated cubes would become
/// one hull that fills the gap between them.
#[test]
fn obj_pieces_become_separate_convex_hulls() {
    for keyword in ["o", "g"] {
        let dir = tempfile::tempdir().unwrap();
        let obj = format!(
            "# two separated cubes\n{keyword} convex_0\n{}{keyword} convex_1\n{}",
            box_obj([-0.1, 0.0, 0.0], [0.02, 0.02, 0.02], 1),
            box_obj([0.1, 0.0, 0.05], [0.01, 0.03, 0.01], 9),
        );
        write(dir.path(), "Thing/collision_vhacd.obj", obj);
        write_object(
            dir.path(),
            "Thing",
            &urdf(
                "Thing",
                0.2,
                None,
                &collision_mesh("collision_vhacd.obj", None, "0 0 0"),
            ),
        );
        let model = load(dir.path(), "Thing").unwrap();
        assert_eq!(
            model.collisions.len(),
            2,
            "'{keyword}' pieces: {:?}",
            model.collisions
        );
        let mut pieces: Vec<_> = model
            .collisions
            .iter()
            .map(|c| bounds(hull_points(&c.shape)))
            .collect();
        pieces.sort_by(|a, b| a.0.x.total_cmp(&b.0.x));
        assert_close(pieces[0].0, [-0.12, -0.02, -0.02], "first cube min");
        assert_close(pieces[0].1, [-0.08, 0.02, 0.02], "first cube max");
        assert_close(pieces[1].0, [0.09, -0.03, 0.04], "second cube min");
        assert_close(pieces[1].1, [0.11, 0.03, 0.06], "second cube max");
    }
}

/// Several `<collision>` elements in one link all count, each with its own origin.
#[test]
fn several_collision_meshes_in_one_link_are_all_kept() {
    let dir = tempfile::tempdir().unwrap();
    write(
        dir.path(),
        "Thing/a.obj",
        box_obj([0.0; 3], [0.01, 0.02, 0.03], 1),
    );
    write(
        dir.path(),
        "Thing/b.obj",
        box_obj([0.0; 3], [0.04, 0.05, 0.06], 1),
    );
    let body = collision_mesh("a.obj", None, "0 0 0") + &collision_mesh("b.obj", None, "0 0 0.2");
    let urdf_path =
        write_object(dir.path(), "Thing", &urdf("Thing", 0.2, None, &body)).join("model.urdf");

    let file = UrdfFile::read(&urdf_path).unwrap();
    let link = file.link_geometry(0).unwrap();
    assert_eq!(link.collisions.len(), 2, "{:?}", link.collisions);
    let (lo_a, hi_a) = bounds(hull_points(&link.collisions[0].shape));
    let (lo_b, hi_b) = bounds(hull_points(&link.collisions[1].shape));
    assert_close(lo_a, [-0.01, -0.02, -0.03], "a.obj min");
    assert_close(hi_a, [0.01, 0.02, 0.03], "a.obj max");
    assert_close(lo_b, [-0.04, -0.05, -0.06], "b.obj min");
    assert_close(hi_b, [0.04, 0.05, 0.06], "b.obj max");
    // The origin stays in the pose, not baked into the points.
    assert_close(
        link.collisions[0].pose.translation,
        [0.0; 3],
        "a.obj origin",
    );
    assert_close(
        link.collisions[1].pose.translation,
        [0.0, 0.0, 0.2],
        "b.obj origin",
    );
}

/// `scale="0.5 2 1"` multiplies each axis separately, for collision and visual meshes alike
/// (the YCB URDFs scale the master chef can by 0.7 and the chips can by 0.95).
#[test]
fn mesh_scale_applies_per_axis() {
    let dir = tempfile::tempdir().unwrap();
    write(
        dir.path(),
        "Thing/cube.obj",
        box_obj([0.0; 3], [0.1, 0.1, 0.1], 1),
    );
    let body = collision_mesh("cube.obj", Some("0.5 2 1"), "0 0 0")
        + r#"<visual><geometry><mesh filename="cube.obj" scale="0.5 2 1"/></geometry></visual>"#;
    write_object(dir.path(), "Thing", &urdf("Thing", 0.2, None, &body));
    let model = load(dir.path(), "Thing").unwrap();

    assert_eq!(model.collisions.len(), 1);
    let (lo, hi) = bounds(hull_points(&model.collisions[0].shape));
    assert_close(lo, [-0.05, -0.2, -0.1], "scaled collision min");
    assert_close(hi, [0.05, 0.2, 0.1], "scaled collision max");

    assert_eq!(model.visuals.len(), 1);
    let Shape::Mesh(mesh) = &model.visuals[0].shape else {
        panic!(
            "a mesh visual must stay a mesh, got {:?}",
            model.visuals[0].shape
        );
    };
    let (lo, hi) = bounds(&mesh.vertices);
    assert_close(lo, [-0.05, -0.2, -0.1], "scaled visual min");
    assert_close(hi, [0.05, 0.2, 0.1], "scaled visual max");
}

/// An STL file (binary or ASCII) is one convex piece.
#[test]
fn stl_collision_is_one_convex_hull() {
    let triangles = tetra_triangles();
    for (file, bytes) in [
        ("tetra.stl", binary_stl(&triangles)),
        ("tetra_ascii.stl", ascii_stl(&triangles).into_bytes()),
    ] {
        let dir = tempfile::tempdir().unwrap();
        write(dir.path(), &format!("Thing/{file}"), bytes);
        write_object(
            dir.path(),
            "Thing",
            &urdf("Thing", 0.05, None, &collision_mesh(file, None, "0 0 0")),
        );
        let model = load(dir.path(), "Thing").unwrap();
        assert_eq!(model.collisions.len(), 1, "{file}: {:?}", model.collisions);
        let points = hull_points(&model.collisions[0].shape);
        // STL repeats shared corners per triangle; what matters is the set of corners.
        let mut distinct: Vec<Vector> = Vec::new();
        for p in points {
            if !distinct.iter().any(|q| (*q - *p).length() < 1e-6) {
                distinct.push(*p);
            }
        }
        assert_eq!(distinct.len(), 4, "{file}: {distinct:?}");
        let (lo, hi) = bounds(points);
        assert_close(lo, [0.0, 0.0, 0.0], &format!("{file} min"));
        assert_close(hi, [0.05, 0.04, 0.03], &format!("{file} max"));
    }
}

// ---------------------------------------------------------------------------------------------
// Mass and friction

/// Bullet's `<contact><lateral_friction>` (which urdf-rs drops) sets μ; without it μ is Bullet's 0.5.
#[test]
fn bullet_friction_and_inertial_mass_are_read() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["Rough", "Plain"] {
        write(
            dir.path(),
            &format!("{name}/cube.obj"),
            box_obj([0.0; 3], [0.02; 3], 1),
        );
    }
    let body = collision_mesh("cube.obj", None, "0 0 0");
    write_object(
        dir.path(),
        "Rough",
        &urdf("Rough", 0.123, Some(0.37), &body),
    );
    write_object(dir.path(), "Plain", &urdf("Plain", 0.25, None, &body));

    let rough = load(dir.path(), "Rough").unwrap();
    assert_eq!(rough.friction, 0.37);
    assert!((rough.mass - 0.123).abs() < 1e-6, "mass {}", rough.mass);

    let plain = load(dir.path(), "Plain").unwrap();
    assert_eq!(DEFAULT_FRICTION, 0.5);
    assert_eq!(plain.friction, 0.5);
    assert!((plain.mass - 0.25).abs() < 1e-6, "mass {}", plain.mass);
}

// ---------------------------------------------------------------------------------------------
// Visual colours

/// Loads an object whose single visual is `visual_xml`, with `files` written beside the URDF,
/// and returns the colour of its visuals (asserting they all share one).
fn visual_color(files: &[(&str, &str)], texture_png: Option<&str>, visual_xml: &str) -> [f32; 3] {
    let dir = tempfile::tempdir().unwrap();
    let object_dir = dir.path().join("Thing");
    for (name, text) in files {
        write(&object_dir, name, text);
    }
    if let Some(png) = texture_png {
        write_red_blue_png(&object_dir.join(png));
    }
    let body = collision_mesh("visual.obj", None, "0 0 0") + visual_xml;
    write_object(dir.path(), "Thing", &urdf("Thing", 0.1, None, &body));
    let model = load(dir.path(), "Thing").unwrap();
    assert!(!model.visuals.is_empty(), "no visuals");
    let color = model.visuals[0].color;
    assert!(model.visuals.iter().all(|v| v.color == color));
    color
}

fn cube() -> String {
    box_obj([0.0; 3], [0.02; 3], 1)
}

#[test]
fn visual_color_comes_from_a_non_white_urdf_material() {
    let material = r#"<material name="teal"><color rgba="0.1 0.6 0.7 1"/></material>"#;
    let color = visual_color(
        &[("visual.obj", &cube())],
        None,
        &visual_mesh("visual.obj", material),
    );
    assert_color(color, [0.1, 0.6, 0.7], "URDF material colour");
}

/// A white URDF material with a texture stands for the texture's colours: use its mean.
#[test]
fn white_urdf_material_with_texture_takes_the_texture_mean() {
    let material =
        r#"<material name="white"><color rgba="1 1 1 1"/><texture filename="tex.png"/></material>"#;
    let color = visual_color(
        &[("visual.obj", &cube())],
        Some("tex.png"),
        &visual_mesh("visual.obj", material),
    );
    assert_color(color, [0.5, 0.0, 0.5], "mean of the URDF texture");
}

/// Without a URDF material the OBJ's own .mtl `Kd` is the colour.
///
/// In OBJ a `usemtl` stays in force across later `o`/`g` lines, so the layouts where the
/// material is named before the object or group must colour it too.
#[test]
fn mtl_diffuse_colour_is_used_without_urdf_material() {
    let mtl = "newmtl paint\nKd 0.2 0.4 0.6\n";
    for header in [
        "usemtl paint\n",
        "o body\nusemtl paint\n",
        "usemtl paint\no body\n",
        "usemtl paint\ng body\n",
    ] {
        let obj = format!("mtllib visual.mtl\n{header}{}", cube());
        let color = visual_color(
            &[("visual.obj", &obj), ("visual.mtl", mtl)],
            None,
            &visual_mesh("visual.obj", ""),
        );
        assert_color(color, [0.2, 0.4, 0.6], &format!(".mtl Kd after {header:?}"));
    }
}

/// The .mtl's `map_Kd` texture gives the mean colour, with or without a white URDF material:
/// the YCB models pair a white `<material>` with textured.obj whose .mtl names the texture.
#[test]
fn mtl_texture_gives_its_mean_colour() {
    let mtl = "newmtl textured\nKa 1 1 1\nKd 1 1 1\nmap_Kd tex.png\n";
    let obj = format!("mtllib visual.mtl\nusemtl textured\n{}", cube());
    let white = r#"<material name="white"><color rgba="1 1 1 1"/></material>"#;
    for material in ["", white] {
        let color = visual_color(
            &[("visual.obj", &obj), ("visual.mtl", mtl)],
            Some("tex.png"),
            &visual_mesh("visual.obj", material),
        );
        assert_color(
            color,
            [0.5, 0.0, 0.5],
            &format!("map_Kd mean ({material:?})"),
        );
    }
}

// ---------------------------------------------------------------------------------------------
// Errors

/// A mesh that is not there is an error naming it (rapier3d-urdf would skip it silently).
#[test]
fn missing_mesh_is_an_error_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let body = collision_mesh("collision_vhacd.obj", None, "0 0 0");
    let urdf_path =
        write_object(dir.path(), "Thing", &urdf("Thing", 0.1, None, &body)).join("model.urdf");

    let err = UrdfFile::read(&urdf_path)
        .unwrap()
        .link_geometry(0)
        .unwrap_err();
    assert!(matches!(err, UrdfError::MissingMesh { .. }), "{err:?}");
    assert!(err.to_string().contains("collision_vhacd.obj"), "{err}");

    // Through the library the same error surfaces.
    let err = load(dir.path(), "Thing").unwrap_err();
    assert!(
        matches!(err, ObjectError::Urdf(UrdfError::MissingMesh { .. })),
        "{err:?}"
    );
    assert!(err.to_string().contains("collision_vhacd.obj"), "{err}");
}

/// A corrupt mesh file is an error that names it, never a panic or an empty object.
#[test]
fn unreadable_meshes_are_errors_naming_the_file() {
    // Deterministic garbage (a small LCG), with no newlines so no line parses as OBJ.
    let mut state = 12345u32;
    let garbage: Vec<u8> = (0..512)
        .map(|_| {
            state = state.wrapping_mul(1_103_515_245).wrapping_add(12345);
            ((state >> 16) as u8) | 0x80
        })
        .collect();
    let cases: Vec<(&str, Vec<u8>)> = vec![
        ("garbage.obj", garbage),
        ("empty.obj", Vec::new()),
        // Face indices past the three vertices that exist.
        (
            "dangling.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n".to_vec(),
        ),
        ("badnumber.obj", b"v 0 0 zero\nf 1 1 1\n".to_vec()),
        // A binary STL cut off inside its second triangle. (A wrong triangle count alone is
        // not an error: mesh-loader trusts the file size, as many real files miscount.)
        ("truncated.stl", {
            let mut bytes = binary_stl(&tetra_triangles()[..2]);
            bytes.truncate(bytes.len() - 20);
            bytes
        }),
    ];
    for (file, bytes) in cases {
        let dir = tempfile::tempdir().unwrap();
        write(dir.path(), &format!("Thing/{file}"), bytes);
        let body = collision_mesh(file, None, "0 0 0");
        write_object(dir.path(), "Thing", &urdf("Thing", 0.1, None, &body));
        let err = load(dir.path(), "Thing").unwrap_err();
        assert!(
            matches!(err, ObjectError::Urdf(UrdfError::BadMesh { .. })),
            "{file}: {err:?}"
        );
        assert!(err.to_string().contains(file), "{file}: {err}");
    }
}

#[test]
fn unknown_object_lists_the_known_ones() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["Alpha", "Beta"] {
        write(
            dir.path(),
            &format!("{name}/cube.obj"),
            box_obj([0.0; 3], [0.02; 3], 1),
        );
        write_object(
            dir.path(),
            name,
            &urdf(name, 0.1, None, &collision_mesh("cube.obj", None, "0 0 0")),
        );
    }
    let err = load(dir.path(), "Nope").unwrap_err();
    assert!(matches!(err, ObjectError::Unknown { .. }), "{err:?}");
    let message = err.to_string();
    assert!(
        message.contains("Nope") && message.contains("Alpha") && message.contains("Beta"),
        "{message}"
    );
    // Path tricks are unknown names too, not a way out of the library.
    assert!(matches!(
        load(dir.path(), "../Alpha"),
        Err(ObjectError::Unknown { .. })
    ));
}

/// An object with only a visual cannot be simulated: reject it.
#[test]
fn object_without_collision_is_rejected() {
    let dir = tempfile::tempdir().unwrap();
    write(
        dir.path(),
        "Ghost/visual.obj",
        box_obj([0.0; 3], [0.02; 3], 1),
    );
    write_object(
        dir.path(),
        "Ghost",
        &urdf("Ghost", 0.1, None, &visual_mesh("visual.obj", "")),
    );
    let err = load(dir.path(), "Ghost").unwrap_err();
    assert!(matches!(err, ObjectError::Invalid { .. }), "{err:?}");
    assert!(err.to_string().contains("collision"), "{err}");
}

// ---------------------------------------------------------------------------------------------
// Bundled assets

/// Objects whose real counterparts are plainly multi-coloured, so their models must be too.
const MULTI_COLOURED: [&str; 5] = [
    "YcbHammer",
    "YcbMediumClamp",
    "YcbMustardBottle",
    "YcbPowerDrill",
    "YcbTomatoSoupCan",
];

#[test]
fn bundled_objects_load_with_geometry_and_their_colours() {
    // Sizes, masses and μ against the reference's table: src/assets/true_size.rs.
    let split = SplitFile::Bundled.read().unwrap();
    let names = split.all();
    assert_eq!(names.len(), 15, "{names:?}");
    let library = ObjectLibrary::bundled();
    for name in &names {
        let model = library.load(name).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(!model.collisions.is_empty(), "{name}: no collisions");
        assert!(!model.visuals.is_empty(), "{name}: no visuals");

        let mut colours: Vec<[f32; 3]> = Vec::new();
        for visual in &model.visuals {
            if !colours.iter().any(|c| {
                c.iter()
                    .zip(visual.color)
                    .all(|(a, b)| (a - b).abs() < 1e-3)
            }) {
                colours.push(visual.color);
            }
        }
        if MULTI_COLOURED.contains(&name.as_str()) {
            assert!(colours.len() >= 2, "{name}: one colour only {colours:?}");
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Simulation

/// An object imported from an OBJ mesh falls into bin 1 and shows up in the camera mask.
#[test]
fn imported_mesh_object_can_be_dropped_and_seen() {
    let dir = tempfile::tempdir().unwrap();
    // A 6 × 4 × 3 cm box, about the size of a small YCB object.
    write(
        dir.path(),
        "MeshBox/box.obj",
        box_obj([0.0; 3], [0.03, 0.02, 0.015], 1),
    );
    let material = r#"<material name="orange"><color rgba="0.9 0.5 0.1 1"/></material>"#;
    let body = collision_mesh("box.obj", None, "0 0 0") + &visual_mesh("box.obj", material);
    write_object(
        dir.path(),
        "MeshBox",
        &urdf("MeshBox", 0.1, Some(0.8), &body),
    );
    let model = load(dir.path(), "MeshBox").unwrap();

    let mut cell = graspmap::sim::Workcell::new(&Default::default()).unwrap();
    cell.drop_objects(&[model], 3).unwrap();
    let frame = cell.capture();
    let visible = frame.mask.iter().filter(|&&id| id == 1).count();
    assert!(visible > 0, "the dropped mesh object is not in the mask");
    assert_eq!(
        cell.locate(0),
        graspmap::sim::ObjectLocation::Bin1,
        "resting at {:?}",
        cell.object_pose(0).translation
    );
    // At rest on the tote floor its centre is half a box side above it (1.5 to 3 cm): the mesh
    // hull, not some stand-in shape, is what touched the floor.
    let height = cell.object_pose(0).translation.z - graspmap::grasp::tote::FLOOR_TOP;
    assert!(
        (0.015 - 0.003..=0.03 + 0.003).contains(&height),
        "centre {height} m above the floor"
    );
}
