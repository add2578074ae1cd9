//! Depth-aware input and clutter labels end to end: the height plane against the scene's geometry,
//! clutter rounds and the object their labels are stored under, depth files under `--check`,
//! `--backfill-depth` and `train --input rgbd`.

use std::path::Path;
use std::process::{Command, Output};

use graspmap::assets::objects::ObjectLibrary;
use graspmap::data::clutter::{round_object_id, round_objects};
use graspmap::data::input::{height_from_depth_mm, read_depth_png};
use graspmap::grasp::tote::FLOOR_TOP;
use graspmap::policy::oracle;
use graspmap::policy::verify::CheckConfig;
use graspmap::sim::Workcell;
use graspmap::vision::camera::Camera;
use graspmap::vision::render::{render, Drawable, Shape};
use rapier3d::math::{Pose, Rotation, Vector};

use crate::common::{assert_ok, assert_user_error};

const BIN: &str = env!("CARGO_BIN_EXE_graspmap");
const TRAIN: [&str; 2] = ["YcbTennisBall", "YcbFoamBrick"];

fn graspmap(dir: &Path, args: &[&str]) -> Output {
    let mut command = Command::new(BIN);
    command.arg("--data").arg(dir.join("data"));
    // Only label and eval read the split; the other commands refuse the flag.
    if matches!(args.first(), Some(&"label" | &"eval")) {
        command.arg("--split").arg(dir.join("split.json"));
    }
    command
        .args(args)
        .env_remove("GRASPMAP_LOG")
        .output()
        .unwrap()
}

#[test]
fn the_height_plane_reads_a_box_of_known_height_in_the_tote() {
    // The workcell's own scene (totes, parked arm) with a 63 mm box on bin 1's floor.
    let cell = Workcell::new(&Default::default()).unwrap();
    let mut scene = cell.drawables();
    let height = 0.063;
    let centre = Vector::new(0.45, 0.12, FLOOR_TOP + height / 2.0);
    scene.push(Drawable {
        shape: Shape::Cuboid {
            half_extents: Vector::new(0.04, 0.05, height / 2.0),
        },
        pose: Pose::from_parts(centre, Rotation::IDENTITY),
        color: [0.8, 0.3, 0.2],
        id: 1,
    });
    let camera = Camera::top_down();
    let frame = render(&camera, &scene);
    let plane = height_from_depth_mm(&frame.to_depth_image_mm());
    let at = |p: Vector| {
        let [u, v, _] = camera.project(p).unwrap();
        i32::from(plane.get_pixel(u as u32, v as u32).0[0])
    };
    for (dx, dy) in [(0.0, 0.0), (0.02, 0.03), (-0.025, -0.035)] {
        let top = at(Vector::new(
            centre.x + dx,
            centre.y + dy,
            FLOOR_TOP + height,
        ));
        assert!(
            (top - 63).abs() <= 2,
            "box top reads {top} mm at ({dx}, {dy})"
        );
    }
    let floor = at(Vector::new(0.6, -0.2, FLOOR_TOP));
    assert!(floor <= 2, "bare floor reads {floor} mm");
}

/// The click the oracle plans on mask id `id` in a clutter round's scene, and the scene's frame.
fn clutter_round(
    j: usize,
    seed: u64,
    on: usize,
) -> (serde_json::Value, graspmap::vision::render::Frame) {
    let library = ObjectLibrary::bundled();
    let models: Vec<_> = TRAIN.iter().map(|n| library.load(n).unwrap()).collect();
    let order = round_objects(j, TRAIN.len(), 2, seed);
    let dropped: Vec<_> = order.iter().map(|&i| models[i].clone()).collect();
    let mut cell = Workcell::new(&Default::default()).unwrap();
    cell.drop_objects(&dropped, seed).unwrap();
    let frame = cell.capture();
    let plan = oracle::plan(
        &Camera::top_down(),
        &frame,
        round_object_id(&order, on),
        &CheckConfig::default(),
    )
    .unwrap();
    let g = plan.grasp;
    let click = serde_json::json!({"object": TRAIN[j], "x": g.u, "y": g.v, "angle": g.angle_deg});
    (click, frame)
}

#[test]
fn a_clutter_label_is_stored_under_the_rounds_object_and_its_depth_is_checked_and_backfilled() {
    let dir = tempfile::tempdir().unwrap();
    let split = serde_json::json!({"train": TRAIN, "test": []});
    std::fs::write(dir.path().join("split.json"), split.to_string()).unwrap();
    // Round 0 of the tennis ball drops both objects; the person clicks the foam brick.
    let seed = 5;
    let (on_brick, frame) = clutter_round(0, seed, 1);
    let (own, _) = clutter_round(1, seed + 100, 1);
    let clicks = dir.path().join("clicks.json");
    std::fs::write(&clicks, serde_json::json!([on_brick, own]).to_string()).unwrap();
    let report = dir.path().join("label.json");
    let args = [
        "label",
        "--clutter",
        "2",
        "--per-object",
        "1",
        "--max-rounds",
        "1",
        "--seed",
        "5",
    ];
    let clicks_arg = [
        "--clicks",
        clicks.to_str().unwrap(),
        "--json",
        report.to_str().unwrap(),
    ];
    assert_ok(&graspmap(
        dir.path(),
        &[&args[..], &clicks_arg[..]].concat(),
    ));

    let labels = dir.path().join("data/labels");
    let stored: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(labels.join("labels.json")).unwrap())
            .unwrap();
    let ball = &stored["YcbTennisBall"][0];
    assert_eq!(
        [&ball[0], &ball[1]],
        [&on_brick["x"], &on_brick["y"]],
        "the brick's grasp is the ball round's label"
    );
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    assert_eq!(
        report["results"]["objects"][0]["lifted_other"], 1,
        "{report}"
    );
    assert_eq!(
        report["results"]["objects"][1]["lifted_other"], 0,
        "{report}"
    );
    // The round replays exactly in another process: same image, same depth.
    let image = image::open(labels.join("YcbTennisBall_1_rgb.png"))
        .unwrap()
        .into_rgb8();
    assert_eq!(image, frame.to_rgb_image());
    let depth_path = labels.join("YcbTennisBall_1_depth.png");
    assert_eq!(
        read_depth_png(&depth_path).unwrap(),
        frame.to_depth_image_mm()
    );

    // One depth file missing: --check names it; --backfill-depth rewrites the same bytes.
    let depth_bytes = std::fs::read(&depth_path).unwrap();
    std::fs::remove_file(&depth_path).unwrap();
    let out = graspmap(dir.path(), &["label", "--check"]);
    assert_eq!(out.status.code(), Some(2));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("YcbTennisBall_1_depth.png: missing depth image"),
        "{stdout}"
    );
    assert_user_error(
        &graspmap(dir.path(), &["train", "--input", "rgbd", "--epochs", "1"]),
        &["YcbTennisBall_1_depth.png: missing", "--backfill-depth"],
    );
    assert_ok(&graspmap(dir.path(), &["label", "--backfill-depth"]));
    assert_eq!(std::fs::read(&depth_path).unwrap(), depth_bytes);
    assert_ok(&graspmap(dir.path(), &["label", "--check"]));

    // A depth file of the wrong kind is reported too.
    image::GrayImage::new(128, 128).save(&depth_path).unwrap();
    let out = graspmap(dir.path(), &["label", "--check"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stdout).contains("16-bit"));
}

#[test]
fn a_reference_dataset_trains_rgb_but_not_rgbd_and_cannot_be_backfilled() {
    let dir = tempfile::tempdir().unwrap();
    let labels = dir.path().join("data/labels");
    std::fs::create_dir_all(&labels).unwrap();
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/reference-labels");
    for entry in std::fs::read_dir(fixture).unwrap().flatten() {
        std::fs::copy(entry.path(), labels.join(entry.file_name())).unwrap();
    }
    std::fs::write(
        dir.path().join("split.json"),
        r#"{"train": ["YcbHammer", "YcbTomatoSoupCan"], "test": []}"#,
    )
    .unwrap();
    assert_user_error(
        &graspmap(dir.path(), &["train", "--input", "rgbd", "--epochs", "1"]),
        &["YcbHammer_1_depth.png: missing"],
    );
    assert_user_error(
        &graspmap(dir.path(), &["label", "--backfill-depth"]),
        &["no progress.json", "cannot be backfilled"],
    );
    assert_user_error(
        &graspmap(dir.path(), &["label", "--clutter", "3"]),
        &["--clutter 3", "only 2 training objects"],
    );
    assert_ok(&graspmap(dir.path(), &["label", "--check"]));
}
