//! Scene files end to end: VPG's test cases placed as listed and at rest, a saved scene replayed
//! byte for byte, `eval --task scenes` with VPG's metrics, and bad scene files refused before
//! any work.

use std::path::{Path, PathBuf};

use graspmap::assets::objects::ObjectLibrary;
use graspmap::assets::urdf::CollisionShape;
use graspmap::data::scene_file::Scene;

use crate::common::{assert_ok, assert_user_error, graspmap};

fn blocks() -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets/blocks")
        .display()
        .to_string()
}

fn vpg_case(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/vpg")
        .join(format!("{name}.txt"))
}

#[test]
fn vpg_cases_keep_the_objects_inside_the_workspace_and_rest_where_listed() {
    let dir = tempfile::tempdir().unwrap();
    for (case, objects) in [
        ("test-10-obj-00", 4),
        ("test-10-obj-03", 5),
        ("test-10-obj-07", 6),
    ] {
        let listed = Scene::read(&vpg_case(case)).unwrap();
        assert_eq!(listed.objects.len(), objects, "{case}");
        let saved = dir.path().join(format!("{case}.json"));
        let out = dir.path().join(format!("{case}.png"));
        let case_path = vpg_case(case);
        let output = graspmap(&[
            "--objects-dir",
            &blocks(),
            "scene",
            "--load",
            case_path.to_str().unwrap(),
            "--save",
            saved.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        assert_ok(&output);
        // Settled, every object is still where VPG lists it: nothing overlapped, nothing
        // floated or sank (VPG lists every block 1 mm above where it rests).
        let settled = Scene::read(&saved).unwrap();
        for (was, now) in listed.objects.iter().zip(&settled.objects) {
            assert_eq!(was.name, now.name);
            let moved: f32 = (0..3)
                .map(|k| (was.position[k] - now.position[k]).powi(2))
                .sum::<f32>()
                .sqrt();
            assert!(
                moved < 0.006,
                "{case}: {} moved {:.1} mm while settling",
                was.name,
                moved * 1000.0
            );
        }
    }
}

#[test]
fn the_grooved_block_collides_as_solid_pieces() {
    let block = ObjectLibrary::new(blocks()).load("Block1").unwrap();
    assert_eq!(block.collisions.len(), 14);
    for piece in &block.collisions {
        let CollisionShape::ConvexHull { points } = &piece.shape else {
            panic!("not a hull: {:?}", piece.shape)
        };
        for axis in 0..3 {
            let values: Vec<f32> = points.iter().map(|p| p.to_array()[axis]).collect();
            let extent = values.iter().cloned().fold(f32::MIN, f32::max)
                - values.iter().cloned().fold(f32::MAX, f32::min);
            // The slabs beside the groove's steep sides are narrow, not flat.
            assert!(
                extent > 0.0005,
                "a piece is flat along axis {axis}: {points:?}"
            );
        }
    }
}

#[test]
fn a_saved_scene_replays_byte_for_byte_and_eval_clears_it_with_vpg_metrics() {
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str| dir.path().join(name).display().to_string();
    assert_ok(&graspmap(&[
        "scene",
        "--objects",
        "YcbTomatoSoupCan,YcbFoamBrick",
        "--seed",
        "4",
        "--save",
        &path("two.json"),
        "--out",
        &path("saved.png"),
    ]));
    assert_ok(&graspmap(&[
        "scene",
        "--load",
        &path("two.json"),
        "--out",
        &path("loaded.png"),
    ]));
    assert_eq!(
        std::fs::read(path("saved.png")).unwrap(),
        std::fs::read(path("loaded.png")).unwrap(),
        "scene --load of a saved scene draws another image"
    );
    let output = graspmap(&[
        "--data",
        &path("data"),
        "eval",
        "--task",
        "scenes",
        "--policy",
        "oracle",
        "--scenes",
        &path("two.json"),
        "--json",
        &path("eval.json"),
    ]);
    assert_ok(&output);
    let stdout = String::from_utf8_lossy(&output.stdout);
    let closing: Vec<&str> = stdout
        .lines()
        .filter(|l| !l.starts_with("report kept in"))
        .collect();
    let last_three = &closing[closing.len() - 3..];
    for (line, start) in
        last_three
            .iter()
            .zip(["completion:", "grasp success:", "action efficiency:"])
    {
        assert!(
            line.starts_with(start) && line.ends_with(" %"),
            "{line:?} in {stdout}"
        );
    }
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(path("eval.json")).unwrap()).unwrap();
    let run = &report["results"]["runs"][0];
    assert_eq!(run["scene"], "two");
    assert_eq!(run["bin"]["locations"].as_object().unwrap().len(), 2);
    let mean = report["results"]["cases"]
        .as_array()
        .unwrap()
        .last()
        .unwrap()
        .clone();
    assert_eq!(mean["scene"], "mean");
    // The oracle alone with two objects apart clears them grasp by grasp.
    assert_eq!(mean["completion"], 1.0, "{run}");
}

#[test]
fn bad_scene_files_are_refused_in_one_line_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, text: &str| {
        let path = dir.path().join(name);
        std::fs::write(&path, text).unwrap();
        path.display().to_string()
    };
    let object = |name: &str, x: &str| {
        format!(
            r#"{{"name": "{name}", "position": [{x}, 0.0, 0.03], "orientation": [0, 0, 0, 1]}}"#
        )
    };
    let json = |objects: &[String]| {
        format!(
            r#"{{"schema": "graspmap.scene/1", "objects": [{}]}}"#,
            objects.join(", ")
        )
    };
    let cases = [
        (
            write("unknown.json", &json(&[object("YcbTeapot", "0.0")])),
            vec!["unknown.json", "unknown object 'YcbTeapot'"],
        ),
        (
            write("malformed.txt", "4.obj 0.3 0.6 0.3 -0.5 0.0\n"),
            vec!["malformed.txt:1", "6 fields, expected 10"],
        ),
        (
            write("outside.json", &json(&[object("YcbFoamBrick", "0.9")])),
            vec!["outside.json", "object 1 (YcbFoamBrick)", "outside bin 1"],
        ),
        (
            write(
                "overlap.json",
                &json(&[
                    object("YcbFoamBrick", "0.0"),
                    object("YcbTomatoSoupCan", "0.01"),
                ]),
            ),
            vec!["overlap.json", "overlap by", "move them apart"],
        ),
        (
            write("nan.txt", "4.obj 0.3 0.6 0.3 -0.5 nan 0.026 0 0 0\n"),
            vec!["nan.txt:1", "'nan' is not a finite number"],
        ),
    ];
    for (file, needles) in cases {
        let report = dir.path().join("never.json");
        let output = graspmap(&[
            "--data",
            dir.path().join("data").to_str().unwrap(),
            "eval",
            "--task",
            "scenes",
            "--policy",
            "random",
            "--scenes",
            &file,
            "--json",
            report.to_str().unwrap(),
        ]);
        assert_user_error(&output, &needles);
        assert!(!report.exists(), "{file}: a report was written");
        let output = graspmap(&[
            "scene",
            "--load",
            &file,
            "--out",
            dir.path().join("never.png").to_str().unwrap(),
        ]);
        assert_user_error(&output, &needles);
    }
}
