//! `graspmap eval` and `predict` end to end: reports, visualisations, determinism and clear errors.

use std::path::{Path, PathBuf};

use crate::common::{assert_ok, assert_user_error, build_commit, graspmap};
use serde_json::Value;

/// A data directory with an untrained (seeded) MiniUNet checkpoint and a split of one training
/// and one test object, so that a whole task is 3 attempts.
pub(crate) struct Setup {
    pub(crate) dir: tempfile::TempDir,
}

impl Setup {
    pub(crate) fn new() -> Self {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("split.json"),
            r#"{"train": ["YcbTomatoSoupCan"], "test": ["YcbFoamBrick"]}"#,
        )
        .unwrap();
        tch::manual_seed(7);
        let vs = tch::nn::VarStore::new(tch::Device::Cpu);
        let _net = graspmap::model::unet::MiniUNet::new(&vs.root());
        let named: Vec<(String, tch::Tensor)> = vs.variables().into_iter().collect();
        std::fs::create_dir_all(dir.path().join("affordance")).unwrap();
        tch::Tensor::write_safetensors(&named, dir.path().join("affordance/best.safetensors"))
            .unwrap();
        Self { dir }
    }

    pub(crate) fn path(&self, name: &str) -> PathBuf {
        self.dir.path().join(name)
    }

    /// Runs graspmap with this data directory, and this split for the commands that read one.
    pub(crate) fn run(&self, args: &[&str]) -> std::process::Output {
        let data = self.dir.path().to_str().unwrap().to_owned();
        let split = self.path("split.json").to_str().unwrap().to_owned();
        // scene and grasp neither read a data directory nor use threads, and refuse both.
        let mut all = match args.first() {
            Some(&"scene" | &"grasp") => Vec::new(),
            _ => vec!["--data", &data, "--threads", "2"],
        };
        if args.iter().any(|a| *a == "eval" || *a == "label") {
            all.extend(["--split", split.as_str()]);
        }
        all.extend_from_slice(args);
        graspmap(&all)
    }

    /// The oracle emptying the default scene in at most `attempts` attempts, plus `extra`.
    pub(crate) fn oracle_empty_bin(&self, attempts: u32, extra: &[&str]) -> std::process::Output {
        let attempts = attempts.to_string();
        let mut args = vec![
            "eval",
            "--task",
            "empty_bin",
            "--policy",
            "oracle",
            "--max-attempts",
            &attempts,
        ];
        args.extend_from_slice(extra);
        self.run(&args)
    }
}

pub(crate) fn read_json(path: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// Rounding slack of f64 seconds: each part is an exact `Duration` turned into an f64.
const CLOCK_SLACK: f64 = 1e-9;

/// One attempt's `timing`: sim, render and network are disjoint intervals measured inside the
/// attempt's wall time (eval's `attempt` times each on its own clock, and the wall clock starts
/// before and stops after all of them), so they are non-negative and add up to no more than it.
fn assert_timing_adds_up(timing: &Value) {
    let part = |name: &str| {
        let value = timing[name]
            .as_f64()
            .unwrap_or_else(|| panic!("{name} is not a number: {timing}"));
        assert!(value.is_finite() && value >= 0.0, "{name}: {timing}");
        value
    };
    let (wall, sim, render, network) = (part("wall"), part("sim"), part("render"), part("network"));
    assert!(wall > 0.0, "{timing}");
    assert!(
        sim + render + network <= wall + CLOCK_SLACK,
        "sim + render + network exceed the wall time: {timing}"
    );
}

/// The results' `timing` summary against every attempt of every run: their count, the mean of
/// each part, the median wall time, and a total that holds every attempt (they run inside it,
/// at most `workers` at a time).
fn assert_summary_matches(results: &Value) {
    let summary = &results["timing"];
    let attempts: Vec<&Value> = results["runs"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|r| r["attempts"].as_array().unwrap())
        .collect();
    assert!(!attempts.is_empty());
    assert_eq!(summary["attempts"], attempts.len(), "{summary}");
    let of = |name: &str| -> Vec<f64> {
        attempts
            .iter()
            .map(|a| a["timing"][name].as_f64().unwrap())
            .collect()
    };
    let close = |a: f64, b: f64| (a - b).abs() <= CLOCK_SLACK;
    for name in ["wall", "sim", "render", "network"] {
        let parts = of(name);
        let mean = parts.iter().sum::<f64>() / parts.len() as f64;
        let reported = summary["mean"][name].as_f64().unwrap();
        assert!(
            close(reported, mean),
            "mean {name} {reported} ≠ {mean}: {summary}"
        );
    }
    let mut walls = of("wall");
    walls.sort_by(f64::total_cmp);
    let mid = walls.len() / 2;
    let median = if walls.len() % 2 == 0 {
        (walls[mid - 1] + walls[mid]) / 2.0
    } else {
        walls[mid]
    };
    let median_wall = summary["median_wall"].as_f64().unwrap();
    assert!(
        close(median_wall, median),
        "median_wall {median_wall} of {walls:?}"
    );
    let total_wall = summary["total_wall"].as_f64().unwrap();
    let workers = summary["workers"].as_f64().unwrap();
    assert!(workers >= 1.0, "{summary}");
    assert!(
        total_wall * workers + CLOCK_SLACK >= walls.iter().sum::<f64>(),
        "total_wall {total_wall} on {workers} workers is less than the attempts' walls {walls:?}"
    );
}

/// What an evaluation decided and how each attempt ended, without the timings.
fn decisions(report: &Value) -> Vec<String> {
    report["results"]["runs"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|run| run["attempts"].as_array().unwrap().clone())
        .map(|a| {
            format!(
                "{} {} {} {} {}",
                a["drop_seed"], a["grasp"], a["choice"], a["reason"], a["held"]
            )
        })
        .collect()
}

#[test]
fn model_eval_reports_its_schema_writes_the_grid_and_repeats_itself() {
    let setup = Setup::new();
    let json = setup.path("eval.json");
    let out = setup.run(&["eval", "--task", "train", "--json", json.to_str().unwrap()]);
    assert_ok(&out);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("YcbTomatoSoupCan"), "{stdout}");
    assert!(stdout.contains("success rate: "), "{stdout}");
    assert!(stdout.contains("95 % CI"), "{stdout}");

    let report = read_json(&json);
    assert_eq!(report["schema"], "graspmap.eval/2");
    assert_eq!(report["git_commit"], build_commit().as_str());
    assert_eq!(report["config"]["seeds"], serde_json::json!([0]));
    assert_eq!(report["config"]["suppression"]["remember"], 0);
    let results = &report["results"];
    assert_eq!(results["task"], "train");
    assert_eq!(results["policy"], "model");
    assert_eq!(results["success"]["trials"], 3);
    let rate = &results["success"];
    assert!(rate["wilson_low"].as_f64().unwrap() <= rate["rate"].as_f64().unwrap());
    assert!(rate["wilson_high"].as_f64().unwrap() >= rate["rate"].as_f64().unwrap());
    assert_eq!(results["per_object"][0]["object"], "YcbTomatoSoupCan");
    assert_eq!(results["per_object"][0]["attempts"], 3);
    let attempts = results["runs"][0]["attempts"].as_array().unwrap();
    // Attempt a of object 0 drops with seed + 100·0 + a + 10000 (the reference's rule).
    let seeds: Vec<u64> = attempts
        .iter()
        .map(|a| a["drop_seed"].as_u64().unwrap())
        .collect();
    assert_eq!(seeds, [10000, 10001, 10002]);
    for a in attempts {
        let angle = a["grasp"]["angle_deg"].as_f64().unwrap();
        assert_eq!(angle % 22.5, 0.0, "model angles are bin angles: {a}");
        assert_eq!(a["choice"]["bin"].as_f64().unwrap() * 22.5, angle);
        assert_timing_adds_up(&a["timing"]);
        assert!(a["timing"]["network"].as_f64().unwrap() > 0.0);
        assert!(a["verified"].is_boolean(), "verification ran: {a}");
    }
    // The report says how many grasps nothing verified were executed, and how many pushed.
    let (pushed, unverified): (Vec<&Value>, Vec<&Value>) = attempts
        .iter()
        .filter(|a| a["verified"] == false)
        .partition(|a| a["reason"] == "pushed");
    assert_eq!(
        stdout.contains("unverified: "),
        !unverified.is_empty(),
        "{} unverified: {stdout}",
        unverified.len()
    );
    assert_eq!(
        stdout.contains("pushed: "),
        !pushed.is_empty(),
        "{} pushed: {stdout}",
        pushed.len()
    );
    // Train drops each attempt's object afresh: nothing to push by default.
    assert_eq!(report["config"]["push_unverified"], false);
    assert!(pushed.is_empty(), "{pushed:?}");
    assert_summary_matches(results);
    for a in 0..3 {
        let vis = setup.path(&format!(
            "affordance/eval_pick_training_vis/YcbTomatoSoupCan_{a}.png"
        ));
        let image = image::open(&vis).unwrap();
        // The best of the 8 angles at 256 px beside the 8 angles at 128, a colour bar below.
        assert_eq!((image.width(), image.height()), (768, 278));
    }

    // The 3 attempts ran 2 at a time; one after another, on one thread, the same grasps,
    // scores and outcomes.
    assert_eq!(results["timing"]["workers"], 2);
    let again = setup.path("again.json");
    assert_ok(&graspmap(&[
        "--data",
        setup.dir.path().to_str().unwrap(),
        "--split",
        setup.path("split.json").to_str().unwrap(),
        "--threads",
        "1",
        "eval",
        "--task",
        "train",
        "--json",
        again.to_str().unwrap(),
    ]));
    let again = read_json(&again);
    assert_eq!(again["results"]["timing"]["workers"], 1);
    assert_summary_matches(&again["results"]);
    assert_eq!(decisions(&report), decisions(&again));
    assert_eq!(report["config"]["centring"], false);
    assert_eq!(report["config"]["verify_top"], 200);
    assert_eq!(report["config"]["verify_floor"], 0.0);
    assert_eq!(report["config"]["verify_rejected"], 200);
    assert_eq!(report["config"]["verify_strips"], 3);
    assert!((report["config"]["verify_square"].as_f64().unwrap() - 0.005).abs() < 1e-6);
    assert!((report["config"]["verify_margin"].as_f64().unwrap() - 0.003).abs() < 1e-6);

    // Centring reports the executed grasp as its own action: angle, bin and map pixel agree.
    let centred = setup.path("centred.json");
    let args = ["eval", "--task", "train", "--centring", "--json"];
    assert_ok(&setup.run(&[&args[..], &[centred.to_str().unwrap()]].concat()));
    let centred = read_json(&centred);
    assert_eq!(centred["config"]["centring"], true);
    for a in centred["results"]["runs"][0]["attempts"]
        .as_array()
        .unwrap()
    {
        let angle = a["grasp"]["angle_deg"].as_f64().unwrap();
        assert_eq!(a["choice"]["bin"].as_f64().unwrap() * 22.5, angle, "{a}");
        assert_eq!(a["choice"]["grasp"], a["grasp"], "{a}");
    }
}

#[test]
fn seeds_aggregate_and_the_random_policy_needs_no_checkpoint() {
    let setup = Setup::new();
    std::fs::remove_file(setup.path("affordance/best.safetensors")).unwrap();
    let json = setup.path("eval.json");
    let out = setup.run(&[
        "eval",
        "--task",
        "test",
        "--policy",
        "random",
        "--seeds",
        "0,1000",
        "--json",
        json.to_str().unwrap(),
    ]);
    assert_ok(&out);
    let results = read_json(&json)["results"].clone();
    assert_eq!(results["seeds"], serde_json::json!([0, 1000]));
    assert_eq!(results["success"]["trials"], 6);
    assert_eq!(results["per_object"][0]["object"], "YcbFoamBrick");
    assert_eq!(results["runs"][1]["attempts"][0]["drop_seed"], 11000);
    assert!(results["runs"][0]["attempts"][0]["vis"].is_null());
}

#[test]
fn empty_bin_counts_moved_left_and_lost_every_attempt() {
    let setup = Setup::new();
    let json = setup.path("eval.json");
    let out = setup.oracle_empty_bin(2, &["--json", json.to_str().unwrap()]);
    assert_ok(&out);
    let stdout = String::from_utf8_lossy(&out.stdout);
    // The scene's progress goes to stderr; stdout carries the results.
    let stderr = String::from_utf8_lossy(&out.stderr);
    let progress: Vec<&str> = stderr
        .lines()
        .filter(|l| l.ends_with("objects moved"))
        .collect();
    assert!(!progress.is_empty() && progress.len() <= 2, "{stderr}");
    assert!(
        progress.iter().all(|l| l.contains("/2 objects moved")),
        "{stderr}"
    );
    assert!(stderr.contains("objects left in the bin."), "{stderr}");
    assert!(!stdout.contains("objects moved\n"), "{stdout}");
    assert!(stdout.contains("left  lost"), "the results table: {stdout}");
    let report = read_json(&json);
    assert_eq!(report["config"]["seeds"], serde_json::json!([2]));
    let bin = &report["results"]["runs"][0]["bin"];
    let total = bin["moved"].as_u64().unwrap()
        + bin["left"].as_u64().unwrap()
        + bin["lost"].as_u64().unwrap();
    assert_eq!(total, 2);
    let last = report["results"]["runs"][0]["attempts"]
        .as_array()
        .unwrap()
        .last()
        .unwrap()
        .clone();
    assert_eq!(last["moved"], bin["moved"]);
    assert_eq!(report["results"]["moved"]["count"], 1);
}

#[test]
fn push_unverified_pushes_where_nothing_verifies_and_pick_success_counts_only_grasps() {
    // All fifteen objects, and only the argmax verified: the untrained network's best grasp in
    // the pile fails the checks within a few attempts.
    let setup = Setup::new();
    let bundled = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/objects/split.json"),
    )
    .unwrap();
    std::fs::write(setup.path("split.json"), bundled).unwrap();
    let json = setup.path("eval.json");
    let args = [
        "eval",
        "--task",
        "empty_bin",
        "--max-attempts",
        "3",
        "--verify-top",
        "1",
    ];
    // Pushing is the default.
    let out = setup.run(&[&args[..], &["--json", json.to_str().unwrap()]].concat());
    assert_ok(&out);
    let report = read_json(&json);
    assert_eq!(report["config"]["push_unverified"], true);
    let results = &report["results"];
    let attempts = results["runs"][0]["attempts"].as_array().unwrap();
    let pushes: Vec<&Value> = attempts
        .iter()
        .filter(|a| a["reason"] == "pushed")
        .collect();
    // The untrained network's best grasps land on bare floor or on both objects at once.
    assert!(!pushes.is_empty(), "no push: {attempts:?}");
    for push in &pushes {
        assert_eq!(push["verified"], false, "{push}");
        assert_eq!(push["success"], false, "{push}");
        let detail = push["detail"].as_str().unwrap();
        // "pushed …" or, where a guard stopped the stroke, "the push stopped: …".
        assert!(detail.contains("push"), "{push}");
    }
    assert_eq!(
        results["success"]["trials"].as_u64().unwrap() as usize,
        attempts.len() - pushes.len()
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    let line = format!("pushed: {} attempt", pushes.len());
    assert!(stdout.contains(&line), "{line:?} missing from {stdout}");

    // `--push-unverified false` executes the first grasp that the default pushed.
    let grasping = setup.path("grasping.json");
    let off = [
        "--push-unverified",
        "false",
        "--json",
        grasping.to_str().unwrap(),
    ];
    assert_ok(&setup.run(&[&args[..], &off[..]].concat()));
    let report = read_json(&grasping);
    assert_eq!(report["config"]["push_unverified"], false);
    let executed = report["results"]["runs"][0]["attempts"].as_array().unwrap();
    let first_push = attempts
        .iter()
        .position(|a| a["reason"] == "pushed")
        .unwrap();
    assert_eq!(executed[first_push]["verified"], false);
    assert_eq!(executed[first_push]["grasp"], attempts[first_push]["grasp"]);
    assert_ne!(executed[first_push]["reason"], "pushed");
    assert!(executed.iter().all(|a| a["reason"] != "pushed"));
}

#[test]
fn give_up_after_ends_a_scene_on_its_first_run_of_failures() {
    let setup = Setup::new();
    let json = setup.path("eval.json");
    let out = setup.run(&[
        "eval",
        "--task",
        "empty_bin",
        "--policy",
        "random",
        "--seeds",
        "1-3",
        "--max-attempts",
        "6",
        "--give-up-after",
        "2",
        "--json",
        json.to_str().unwrap(),
    ]);
    assert_ok(&out);
    let report = read_json(&json);
    assert_eq!(report["config"]["give_up_after"], 2);
    let mut gave_up = 0;
    for run in report["results"]["runs"].as_array().unwrap() {
        let failed: Vec<bool> = run["attempts"]
            .as_array()
            .unwrap()
            .iter()
            .map(|a| !a["success"].as_bool().unwrap())
            .collect();
        let first_pair = failed.windows(2).position(|w| w[0] && w[1]);
        if run["bin"]["gave_up"].as_bool().unwrap() {
            gave_up += 1;
            assert_eq!(first_pair, Some(failed.len() - 2), "{run}");
        } else {
            assert_eq!(first_pair, None, "{run}");
            assert!(failed.len() == 6 || run["bin"]["left"] == 0, "{run}");
        }
    }
    assert!(
        gave_up > 0,
        "the random policy fails twice in a row somewhere"
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("gave up after 2 failed attempts in a row."),
        "{stderr}"
    );
}

#[test]
fn predict_prints_a_grasp_and_writes_the_grid() {
    let setup = Setup::new();
    let scene = setup.path("scene.png");
    assert_ok(&graspmap(&[
        "scene",
        "--objects",
        "YcbTomatoSoupCan",
        "--seed",
        "3",
        "--out",
        scene.to_str().unwrap(),
    ]));
    let json = setup.path("predict.json");
    let vis = setup.path("grid.png");
    let out = setup.run(&[
        "predict",
        "--image",
        scene.to_str().unwrap(),
        "--out",
        vis.to_str().unwrap(),
        "--json",
        json.to_str().unwrap(),
    ]);
    assert_ok(&out);
    assert!(String::from_utf8_lossy(&out.stdout).contains("grasp x "));
    let report = read_json(&json);
    assert_eq!(report["schema"], "graspmap.predict/1");
    let results = &report["results"];
    assert!(results["x"].as_u64().unwrap() < 128 && results["y"].as_u64().unwrap() < 128);
    assert_eq!(results["angle"].as_f64().unwrap() % 22.5, 0.0);
    let score = results["score"].as_f64().unwrap();
    assert!((0.0..=1.0).contains(&score));
    assert_eq!(image::open(&vis).unwrap().width(), 768);
}

#[test]
fn bad_inputs_are_one_line_errors_with_exit_status_2() {
    let setup = Setup::new();
    std::fs::remove_file(setup.path("affordance/best.safetensors")).unwrap();
    let out = setup.run(&["eval", "--task", "test"]);
    assert_user_error(&out, &["best.safetensors", "graspmap train"]);
    let out = setup.run(&["eval", "--task", "tests"]);
    assert_user_error(&out, &["tests", "empty_bin"]);
    let out = setup.run(&["eval", "--task", "empty_bin", "--seeds", "9-3"]);
    assert_user_error(&out, &["9-3"]);
    // Centring reads the depth image through the full collision check: asked for without it,
    // it is refused rather than silently ignored.
    let out = setup.run(&[
        "eval",
        "--task",
        "test",
        "--centring",
        "--collision-check",
        "walls",
    ]);
    assert_user_error(&out, &["--centring", "--collision-check full", "walls"]);
    let out = setup.run(&["eval", "--task", "test", "--verify-floor", "1.5"]);
    assert_user_error(&out, &["1.5", "fraction from 0 to 1"]);
    // Both options belong to verification, which --verify-top 0 turns off.
    for (flag, value) in [("--verify-floor", "0.25"), ("--verify-rejected", "50")] {
        let out = setup.run(&["eval", "--task", "test", "--verify-top", "0", flag, value]);
        assert_user_error(&out, &[&format!("{flag} {value}"), "--verify-top 0"]);
    }
    // --resume continues the report of the same task and policy (--json, else the kept copy).
    let other = setup.path("other_task.json");
    let json = other.to_str().unwrap();
    let out = setup.run(&[
        "--json", json, "eval", "--task", "train", "--policy", "random",
    ]);
    assert_ok(&out);
    let out = setup.run(&[
        "--json",
        other.to_str().unwrap(),
        "eval",
        "--task",
        "test",
        "--policy",
        "random",
        "--resume",
    ]);
    assert_user_error(&out, &["--task train", "--task test"]);
    // A report with a field missing is refused, naming the file and the field, never read as if
    // the field were empty.
    let partial = setup.path("partial.json");
    std::fs::write(
        &partial,
        r#"{"schema": "graspmap.eval/2", "config": {"task": "test", "policy": "random"}, "results": {"runs": []}}"#,
    )
    .unwrap();
    let json = partial.to_str().unwrap();
    let out = setup.run(&[
        "--json", json, "eval", "--task", "test", "--policy", "random", "--resume",
    ]);
    assert_user_error(&out, &["partial.json", "missing field", "drop --resume"]);
    let corrupt = setup.path("corrupt.safetensors");
    std::fs::write(&corrupt, b"not a checkpoint").unwrap();
    let out = setup.run(&[
        "eval",
        "--task",
        "test",
        "--checkpoint",
        corrupt.to_str().unwrap(),
    ]);
    assert_user_error(&out, &["corrupt.safetensors"]);

    let checkpoint = Setup::new();
    let small = setup.path("small.png");
    image::RgbImage::new(64, 64).save(&small).unwrap();
    let out = checkpoint.run(&["predict", "--image", small.to_str().unwrap()]);
    assert_user_error(&out, &["small.png", "64×64", "128×128"]);
    let grey = setup.path("grey.png");
    image::GrayImage::new(128, 128).save(&grey).unwrap();
    let out = checkpoint.run(&["predict", "--image", grey.to_str().unwrap()]);
    assert_user_error(&out, &["grey.png", "RGB"]);
    let text = setup.path("notes.png");
    std::fs::write(&text, b"hello").unwrap();
    let out = checkpoint.run(&["predict", "--image", text.to_str().unwrap()]);
    assert_user_error(&out, &["notes.png"]);
    let out = checkpoint.run(&["predict", "--image", "/nonexistent/photo.png"]);
    assert_user_error(&out, &["/nonexistent/photo.png"]);
}

#[test]
fn record_writes_the_episode_beside_the_camera_view() {
    let setup = Setup::new();
    let gif = setup.path("episode.gif");
    let out = setup.oracle_empty_bin(1, &["--record", gif.to_str().unwrap()]);
    assert_ok(&out);
    let decoder = image::codecs::gif::GifDecoder::new(std::io::BufReader::new(
        std::fs::File::open(&gif).unwrap(),
    ))
    .unwrap();
    let frames = image::AnimationDecoder::into_frames(decoder)
        .collect_frames()
        .unwrap();
    assert!(frames.len() > 10, "{} frames", frames.len());
    // The oblique view (320 × 240) and the camera view scaled to 240 × 240.
    assert_eq!(frames[0].buffer().dimensions(), (560, 240));
    let out = setup.run(&[
        "eval", "--task", "test", "--seeds", "1-2", "--record", "x.gif",
    ]);
    assert_user_error(&out, &["--record", "--seeds"]);
}

/// The attempts of a report without their timings: what must not change on resume.
fn attempts_of(report: &Value) -> Vec<Value> {
    report["results"]["runs"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|run| run["attempts"].as_array().unwrap().clone())
        .map(|mut a| {
            a.as_object_mut().unwrap().remove("timing");
            a
        })
        .collect()
}

#[test]
fn ctrl_c_keeps_the_finished_scenes_and_resume_equals_an_uninterrupted_sweep() {
    use std::io::BufRead;
    let setup = Setup::new();
    let sweep = |json: &Path| -> Vec<String> {
        [
            "--data",
            setup.dir.path().to_str().unwrap(),
            "--split",
            setup.path("split.json").to_str().unwrap(),
            "--json",
            json.to_str().unwrap(),
            "eval",
            "--task",
            "empty_bin",
            "--policy",
            "random",
            "--seeds",
            "1-5",
            "--max-attempts",
            "2",
        ]
        .map(str::to_owned)
        .to_vec()
    };
    let whole = setup.path("whole.json");
    assert_ok(&graspmap(
        &sweep(&whole).iter().map(String::as_str).collect::<Vec<_>>(),
    ));

    let report = setup.path("sweep.json");
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_graspmap"))
        .args(sweep(&report))
        .env_remove("GRASPMAP_LOG")
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // The first scene is done when it says (on stderr, with what the run kept) how many
    // objects it left.
    let mut lines = std::io::BufReader::new(child.stderr.take().unwrap()).lines();
    for line in lines.by_ref() {
        if line.unwrap().ends_with("objects left in the bin.") {
            break;
        }
    }
    crate::common::send_signal(&child, libc::SIGINT);
    let said: Vec<String> = lines.map(Result::unwrap).collect();
    assert_eq!(child.wait().unwrap().code(), Some(130), "{said:?}");
    assert!(
        said.iter()
            .any(|l| l.contains("rerun the same command with --resume")),
        "{said:?}"
    );
    let partial: Value = serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    assert_eq!(partial["schema"], "graspmap.eval/2");
    assert_eq!(partial["results"]["interrupted"], true);
    let kept = partial["results"]["runs"].as_array().unwrap().len();
    assert!((1..5).contains(&kept), "{kept} scenes kept");

    let mut resume = sweep(&report);
    resume.push("--resume".into());
    assert_ok(&graspmap(
        &resume.iter().map(String::as_str).collect::<Vec<_>>(),
    ));
    let resumed: Value = serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    let uninterrupted: Value =
        serde_json::from_str(&std::fs::read_to_string(&whole).unwrap()).unwrap();
    assert_eq!(resumed["results"]["interrupted"], false);
    assert_eq!(attempts_of(&resumed), attempts_of(&uninterrupted));
    assert_eq!(
        resumed["results"]["success"],
        uninterrupted["results"]["success"]
    );
    assert_eq!(
        resumed["results"]["moved"],
        uninterrupted["results"]["moved"]
    );
}
