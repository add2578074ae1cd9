//! Placing in bin 2 with objects that users bring: mesh objects, written at test time from the
//! bundled models' collision shapes, each shape a convex piece of one OBJ (as a V-HACD file has
//! them) and the object's frame moved below its mesh, as the public YCB clamp's lies 28–57 mm
//! below its own.

use std::path::Path;

use graspmap::assets::objects::{ObjectLibrary, ObjectModel};
use graspmap::assets::urdf::CollisionShape;
use graspmap::grasp::tote::FLOOR_TOP;
use graspmap::grasp::world::world_grasp;
use graspmap::policy::oracle;
use graspmap::policy::verify::CheckConfig;
use graspmap::sim::{ObjectLocation, Workcell};
use graspmap::vision::camera::Camera;
use rapier3d::math::{Pose, Rotation, Vector};

use crate::common::{assert_ok, graspmap};

/// How far below its mesh each written object's frame lies (m).
const FRAME_BELOW_MESH: f32 = 0.04;

/// Facets around a round piece, as the simulator facets the bundled ones.
const FACETS: usize = 24;

/// The points of one collision piece, in its own frame.
fn piece_points(shape: &CollisionShape) -> Vec<Vector> {
    let ring = |r: f32, y: f32| {
        (0..FACETS).map(move |i| {
            let a = i as f32 * std::f32::consts::TAU / FACETS as f32;
            Vector::new(r * a.cos(), y, r * a.sin())
        })
    };
    let ball = |r: f32, half: f32| {
        let mut points = vec![
            Vector::new(0.0, r + half, 0.0),
            Vector::new(0.0, -r - half, 0.0),
        ];
        for band in 1..FACETS / 4 {
            let polar = band as f32 * std::f32::consts::FRAC_PI_2 / (FACETS / 4) as f32;
            points.extend(ring(r * polar.sin(), half + r * polar.cos()));
            points.extend(ring(r * polar.sin(), -half - r * polar.cos()));
        }
        points.extend(ring(r, half));
        points.extend(ring(r, -half));
        points
    };
    match shape {
        CollisionShape::Cuboid { half_extents: h } => (0..8)
            .map(|i| {
                let s = |bit: usize| if i & bit == 0 { -1.0 } else { 1.0 };
                Vector::new(s(1) * h.x, s(2) * h.y, s(4) * h.z)
            })
            .collect(),
        CollisionShape::Sphere { radius } => ball(*radius, 0.0),
        CollisionShape::Capsule {
            radius,
            half_height,
        } => ball(*radius, *half_height),
        CollisionShape::Cylinder {
            radius,
            half_height,
        } => ring(*radius, -*half_height)
            .chain(ring(*radius, *half_height))
            .collect(),
        CollisionShape::ConvexHull { points } => points.clone(),
    }
}

/// Writes bundled object `name` into `dir` as a mesh object: `<name>/model.urdf` and
/// `<name>/pieces.obj`, one `o` block (a closed convex hull) per collision piece of the bundled
/// model, every vertex [`FRAME_BELOW_MESH`] above the frame, mass, friction and colour kept.
fn write_mesh_object(dir: &Path, name: &str) -> ObjectModel {
    let bundled = ObjectLibrary::bundled().load(name).unwrap();
    let mut obj = String::new();
    let mut first = 1;
    for (k, piece) in bundled.collisions.iter().enumerate() {
        let points: Vec<Vector> = piece_points(&piece.shape)
            .into_iter()
            .map(|p| piece.pose.transform_point(p) + Vector::new(0.0, 0.0, FRAME_BELOW_MESH))
            .collect();
        let (vertices, triangles) = rapier3d::parry::transformation::convex_hull(&points);
        obj += &format!("o piece_{k}\n");
        for v in &vertices {
            obj += &format!("v {} {} {}\n", v.x, v.y, v.z);
        }
        for t in &triangles {
            let [a, b, c] = t.map(|i| i as usize + first);
            obj += &format!("f {a} {b} {c}\n");
        }
        first += vertices.len();
    }
    let [r, g, b] = bundled.visuals[0].color;
    let urdf = format!(
        r#"<?xml version="1.0"?>
<robot name="{name}">
  <link name="baseLink">
    <contact><lateral_friction value="{mu}"/></contact>
    <inertial><origin xyz="0 0 0" rpy="0 0 0"/><mass value="{mass}"/>
      <inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1e-4"/></inertial>
    <visual><geometry><mesh filename="pieces.obj"/></geometry>
      <material name="c"><color rgba="{r} {g} {b} 1"/></material></visual>
    <collision><geometry><mesh filename="pieces.obj"/></geometry></collision>
  </link>
</robot>
"#,
        mu = bundled.friction,
        mass = bundled.mass,
    );
    let object_dir = dir.join(name);
    std::fs::create_dir_all(&object_dir).unwrap();
    std::fs::write(object_dir.join("pieces.obj"), obj).unwrap();
    std::fs::write(object_dir.join("model.urdf"), urdf).unwrap();
    ObjectLibrary::new(dir).load(name).unwrap()
}

/// The bundled split's train and test objects.
fn bundled_names() -> (Vec<String>, Vec<String>) {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/assets/objects/split.json"
    ))
    .unwrap();
    let split: serde_json::Value = serde_json::from_str(&text).unwrap();
    let names = |key: &str| -> Vec<String> {
        split[key]
            .as_array()
            .unwrap()
            .iter()
            .map(|n| n.as_str().unwrap().to_owned())
            .collect()
    };
    (names("train"), names("test"))
}

#[test]
fn a_light_faceted_mesh_released_over_a_pile_of_ten_in_bin_2_rests_on_its_floor() {
    let dir = tempfile::tempdir().unwrap();
    // A 58 g ball of 24-sided facets: what rolls furthest off a pile.
    let ball = write_mesh_object(dir.path(), "YcbTennisBall");
    let library = ObjectLibrary::bundled();
    let mut cell = Workcell::new(&Default::default()).unwrap();
    // Ten objects dropped one after another onto one point of bin 2, where every object used to
    // be dropped from 0.65 m.
    let pile = [
        "YcbPowerDrill",
        "YcbMustardBottle",
        "YcbChipsCan",
        "YcbMasterChefCan",
        "YcbPottedMeatCan",
        "YcbGelatinBox",
        "YcbFoamBrick",
        "YcbTomatoSoupCan",
        "YcbBanana",
        "YcbHammer",
    ];
    for (k, name) in pile.iter().enumerate() {
        let tilt = Rotation::from_euler(
            rapier3d::glamx::EulerRot::ZYX,
            0.7 * k as f32,
            0.4 * (k % 3) as f32,
            0.3 * (k % 2) as f32,
        );
        let at = Vector::new(-0.49, -0.11, 0.25 + 0.03 * k as f32);
        cell.add_object(&library.load(name).unwrap(), Pose::from_parts(at, tilt))
            .unwrap();
        cell.settle(4.0);
    }
    for (k, name) in pile.iter().enumerate() {
        assert_eq!(
            cell.locate(k),
            ObjectLocation::Bin2,
            "{name} left the pile's bin"
        );
    }
    let highest = (0..pile.len())
        .map(|k| cell.object_centre(k).z)
        .fold(0.0, f32::max);
    assert!(
        highest > FLOOR_TOP + 0.08,
        "the pile is only {highest} m high"
    );
    let index = cell
        .add_object(&ball, Pose::from_translation(Vector::new(0.5, 0.0, 0.0)))
        .unwrap();
    cell.settle(3.0);
    assert_eq!(cell.locate(index), ObjectLocation::Bin1);

    let pile_before: Vec<Vector> = (0..pile.len()).map(|k| cell.object_centre(k)).collect();
    let camera = Camera::top_down();
    let frame = cell.capture();
    let plan = oracle::plan(&camera, &frame, index as u16 + 1, &CheckConfig::default()).unwrap();
    let outcome = cell.pick(&world_grasp(&camera, &frame, plan.grasp));

    assert!(outcome.success, "{outcome:?}");
    assert_eq!(outcome.placed, Some(ObjectLocation::Bin2), "{outcome:?}");
    assert_eq!(cell.locate(index), ObjectLocation::Bin2);
    // Released low over free floor beside the pile, not dropped onto it: it rests on the floor
    // (a 64 mm ball's centre 32 mm up) within a few centimetres of where the hand let it go,
    // and the pile is where it was.
    let rests = cell.object_centre(index);
    assert!(
        rests.z < FLOOR_TOP + 0.04,
        "the ball rests {rests:?}, on the pile"
    );
    let released = Vector::from_array(outcome.released_at.unwrap());
    assert!(
        released.z - rests.z < 0.05 && (released - rests).truncate().length() < 0.05,
        "released at {released:?}, came to rest at {rests:?}"
    );
    for (k, before) in pile_before.iter().enumerate() {
        assert_eq!(
            cell.locate(k),
            ObjectLocation::Bin2,
            "{} left bin 2",
            pile[k]
        );
        let moved = (cell.object_centre(k) - *before).length();
        assert!(moved < 0.002, "{} moved {moved} m", pile[k]);
    }
}

#[test]
fn fifteen_mesh_objects_empty_bin_1_and_every_carried_object_rests_in_bin_2() {
    let dir = tempfile::tempdir().unwrap();
    let objects = dir.path().join("objects");
    let (train, test) = bundled_names();
    for name in train.iter().chain(&test) {
        write_mesh_object(&objects, name);
    }
    std::fs::write(
        objects.join("split.json"),
        serde_json::json!({ "train": train, "test": test }).to_string(),
    )
    .unwrap();
    let report = dir.path().join("empty_bin.json");
    let output = graspmap(&[
        "--data",
        dir.path().join("data").to_str().unwrap(),
        "--objects-dir",
        objects.to_str().unwrap(),
        "--quiet",
        "--json",
        report.to_str().unwrap(),
        "eval",
        "--task",
        "empty_bin",
        "--policy",
        "oracle",
        "--n_past_action",
        "8",
        "--seeds",
        "1",
    ]);
    assert_ok(&output);
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    let run = &report["results"]["runs"][0];
    let locations = run["bin"]["locations"].as_object().unwrap();
    assert_eq!(locations.len(), 15);
    let mut carried = 0u64;
    for attempt in run["attempts"].as_array().unwrap() {
        if attempt["success"] == true {
            carried += 1;
            let held = attempt["held"].as_str().unwrap();
            assert_eq!(
                attempt["placed"], "bin2",
                "{held} was carried but not placed: {attempt}"
            );
            assert_eq!(locations[held], "bin2", "{held} left bin 2 later");
        } else {
            assert!(attempt.get("placed").is_none(), "{attempt}");
        }
    }
    // A real emptying, every object found in one of the bins: the frames 40 mm below the meshes
    // count nothing as lost.
    assert!(carried >= 10, "only {carried} objects carried");
    assert!(
        run["bin"]["moved"].as_u64().unwrap() >= carried,
        "{locations:?}"
    );
    assert_eq!(run["bin"]["lost"], 0, "{locations:?}");
}
