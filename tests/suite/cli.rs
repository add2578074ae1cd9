//! The `graspmap` binary end to end: outputs, JSON reports and one-line errors with exit status 2.

use crate::common::{assert_user_error, build_commit, graspmap};

#[test]
fn unknown_object_names_it_and_lists_the_known_ones() {
    let out = graspmap(&["grasp", "--object", "YcbNope", "--oracle"]);
    assert_user_error(&out, &["YcbNope", "YcbMustardBottle"]);
}

#[test]
fn pixel_outside_the_image_is_rejected() {
    let out = graspmap(&[
        "grasp", "--object", "YcbPear", "--pixel", "200,3", "--angle", "0",
    ]);
    assert_user_error(&out, &["200,3", "128"]);
}

#[test]
fn bad_flag_values_are_rejected() {
    let out = graspmap(&[
        "grasp", "--object", "YcbPear", "--pixel", "3,3", "--angle", "steep",
    ]);
    assert_user_error(&out, &["steep"]);
    let out = graspmap(&["grasp", "--object", "YcbPear", "--oracle", "--seed", "-4"]);
    assert_user_error(&out, &["-4"]);
    let out = graspmap(&["--threads", "0", "grasp", "--object", "YcbPear", "--oracle"]);
    assert_user_error(&out, &["0"]);
    let out = graspmap(&[
        "grasp",
        "--object",
        "YcbPear",
        "--oracle",
        "--grip-force",
        "-3",
    ]);
    assert_user_error(&out, &["-3"]);
}

#[test]
fn a_grasp_needs_exactly_one_way_to_choose_it() {
    let out = graspmap(&["grasp", "--object", "YcbPear"]);
    assert_user_error(&out, &["--oracle"]);
    let out = graspmap(&["grasp", "--object", "YcbPear", "--oracle", "--random"]);
    assert_user_error(&out, &["--random"]);
}

#[test]
fn missing_objects_dir_and_broken_urdf_are_named() {
    let out = graspmap(&[
        "--objects-dir",
        "/no/such/dir",
        "scene",
        "--objects",
        "A",
        "--out",
        "x.png",
    ]);
    assert_user_error(&out, &["/no/such/dir"]);

    let dir = tempfile::tempdir().unwrap();
    let object = dir.path().join("Broken");
    std::fs::create_dir(&object).unwrap();
    std::fs::write(
        object.join("model.urdf"),
        "<robot name='Broken'><link name='a'>",
    )
    .unwrap();
    let out = graspmap(&[
        "--objects-dir",
        dir.path().to_str().unwrap(),
        "grasp",
        "--object",
        "Broken",
        "--oracle",
    ]);
    assert_user_error(&out, &["model.urdf"]);
}

#[test]
fn scene_writes_a_camera_image_and_a_millimetre_depth_image() {
    let dir = tempfile::tempdir().unwrap();
    let rgb = dir.path().join("scene.png");
    let depth = dir.path().join("depth.png");
    let out = graspmap(&[
        "scene",
        "--objects",
        "YcbTennisBall,YcbGelatinBox",
        "--seed",
        "4",
        "--out",
        rgb.to_str().unwrap(),
        "--depth",
        depth.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let image = image::open(&rgb).unwrap();
    assert_eq!((image.width(), image.height()), (128, 128));
    assert!(matches!(image, image::DynamicImage::ImageRgb8(_)));
    let depth = image::open(&depth).unwrap().into_luma16();
    // Looking straight down from 0.70711 m, the middle of the bin floor (z = 0.02) is 687 mm away,
    // unless an object lies there.
    let corner = depth.get_pixel(30, 95).0[0];
    assert!((680..=690).contains(&corner), "floor depth {corner} mm");
}

#[test]
fn grasp_json_report_has_its_schema_and_fields() {
    let out = graspmap(&[
        "grasp",
        "--object",
        "YcbTennisBall",
        "--seed",
        "1",
        "--oracle",
        "--json",
        "-",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: serde_json::Value =
        serde_json::from_slice(&out.stdout).expect("stdout is exactly the JSON report");
    assert_eq!(report["schema"], "graspmap.grasp/1");
    assert_eq!(report["seed"], 1);
    assert_eq!(report["git_commit"], build_commit().as_str());
    let r = &report["results"];
    assert_eq!(r["object"], "YcbTennisBall");
    assert!(r["success"].is_boolean());
    assert!(r["reason"].is_string());
    assert_eq!(r["pixel"].as_array().unwrap().len(), 2);
    assert!(r["angle_deg"].as_f64().unwrap() < 180.0);
    assert!(r["sim_seconds"].as_f64().unwrap() > 1.0);
    let wall = r["wall_seconds"].as_f64().unwrap();
    assert!(wall > 0.0);
    // The camera image is rendered inside the timed run, drop to placed.
    let render = r["render_seconds"].as_f64().unwrap();
    assert!(
        (0.0..=wall).contains(&render),
        "render {render} s of {wall} s"
    );
    assert_eq!(report["config"]["workcell"]["grip_force"], 40.0);
    // The human-readable line went to stderr.
    assert!(String::from_utf8_lossy(&out.stderr).contains("YcbTennisBall seed 1"));
}

#[test]
fn the_same_seed_gives_the_same_report_and_image() {
    let dir = tempfile::tempdir().unwrap();
    let run = |name: &str| {
        let image = dir.path().join(name);
        let out = graspmap(&[
            "grasp",
            "--object",
            "YcbBanana",
            "--seed",
            "5",
            "--random",
            "--json",
            "-",
            "--image",
            image.to_str().unwrap(),
        ]);
        assert!(out.status.success());
        let mut report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        report["results"]["wall_seconds"] = 0.into();
        report["results"]["render_seconds"] = 0.into();
        (report["results"].clone(), std::fs::read(&image).unwrap())
    };
    assert_eq!(run("a.png"), run("b.png"));
}

#[test]
fn record_writes_an_animated_gif_of_the_attempt() {
    let dir = tempfile::tempdir().unwrap();
    let gif = dir.path().join("pick.gif");
    let out = graspmap(&[
        "grasp",
        "--object",
        "YcbFoamBrick",
        "--seed",
        "2",
        "--oracle",
        "--record",
        gif.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let file = std::fs::File::open(&gif).unwrap();
    let decoder = image::codecs::gif::GifDecoder::new(std::io::BufReader::new(file)).unwrap();
    let frames = image::AnimationDecoder::into_frames(decoder)
        .collect_frames()
        .unwrap();
    assert!(frames.len() > 20, "only {} frames", frames.len());
    // The arm moves: first and middle frames differ.
    assert_ne!(frames[0].buffer(), frames[frames.len() / 2].buffer());
    // The atomic writer's temporary (.pick.gif.tmp-<pid>) is renamed away.
    let leftovers: Vec<String> = std::fs::read_dir(gif.parent().unwrap())
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|name| name.contains(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");
}
