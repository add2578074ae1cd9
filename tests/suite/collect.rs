//! `graspmap collect`, `merge` and `train --trials` end to end: the trial store's bytes, resume
//! after a kill, `--check`, shards that merge into the unsharded store, and the refusals.

use std::path::{Path, PathBuf};

use crate::common::{assert_ok, assert_user_error, graspmap, send_signal};
use crate::eval::read_json;

const TRAIN: [&str; 3] = ["YcbTomatoSoupCan", "YcbFoamBrick", "YcbGelatinBox"];
const TEST: [&str; 2] = ["YcbBanana", "YcbHammer"];

/// A data directory with an untrained (seeded) checkpoint and a split of three training and two
/// test objects.
struct Setup {
    dir: tempfile::TempDir,
}

impl Setup {
    fn new() -> Self {
        let dir = tempfile::tempdir().unwrap();
        let split = serde_json::json!({ "train": TRAIN, "test": TEST });
        std::fs::write(dir.path().join("split.json"), split.to_string()).unwrap();
        tch::manual_seed(11);
        let vs = tch::nn::VarStore::new(tch::Device::Cpu);
        let _net = graspmap::model::unet::MiniUNet::new(&vs.root());
        let named: Vec<(String, tch::Tensor)> = vs.variables().into_iter().collect();
        std::fs::create_dir_all(dir.path().join("affordance")).unwrap();
        tch::Tensor::write_safetensors(&named, dir.path().join("affordance/best.safetensors"))
            .unwrap();
        Self { dir }
    }

    fn path(&self, name: &str) -> PathBuf {
        self.dir.path().join(name)
    }

    /// `collect` of 4 small scenes (2 objects, at most 2 attempts) into `out`, plus `extra`.
    fn args(&self, out: &str, threads: &str, extra: &[&str]) -> Vec<String> {
        let mut args: Vec<String> = [
            "--data",
            self.dir.path().to_str().unwrap(),
            "--split",
            self.path("split.json").to_str().unwrap(),
            "--threads",
            threads,
            "collect",
            "--out",
            self.path(out).to_str().unwrap(),
            "--scenes",
            "4",
            "--clutter",
            "2",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        // Exploring is the model's: the oracle and random policies refuse --explore.
        if !extra.contains(&"oracle") && !extra.contains(&"random") {
            args.extend(["--explore".to_owned(), "0.5".to_owned()]);
        }
        if !extra.contains(&"--seed") {
            args.extend(["--seed".to_owned(), "5".to_owned()]);
        }
        if !extra.contains(&"--max-attempts") {
            args.extend(["--max-attempts".to_owned(), "2".to_owned()]);
        }
        args.extend(extra.iter().map(|s| s.to_string()));
        args
    }

    fn collect(&self, out: &str, extra: &[&str]) -> std::process::Output {
        let args = self.args(out, "2", extra);
        graspmap(&args.iter().map(String::as_str).collect::<Vec<_>>())
    }
}

/// Every file of a store but the writer's lock, by relative path, with its bytes.
fn store_bytes(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut files = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(folder) = stack.pop() {
        for entry in std::fs::read_dir(&folder).unwrap().flatten() {
            let path = entry.path();
            if path.is_dir() {
                stack.push(path);
            } else if entry.file_name() != ".lock" {
                let name = path
                    .strip_prefix(dir)
                    .unwrap()
                    .to_string_lossy()
                    .into_owned();
                files.push((name, std::fs::read(&path).unwrap()));
            }
        }
    }
    files.sort();
    files
}

#[test]
fn collect_stores_every_attempt_of_training_objects_and_repeats_itself_byte_for_byte() {
    let setup = Setup::new();
    let json = setup.path("collect.json");
    let out = setup.collect("trials", &["--json", json.to_str().unwrap()]);
    assert_ok(&out);
    let report = read_json(&json);
    let trials = report["results"]["trials"].as_u64().unwrap();
    assert!(trials >= 4, "{report}");
    assert_eq!(report["results"]["scenes"], 4);

    let store = setup.path("trials");
    let mut policies = std::collections::BTreeSet::new();
    let mut failures = 0;
    for scene in 0..4 {
        let record = read_json(&store.join(format!("scene_{scene:06}/trials.json")));
        assert_eq!(record["complete"], true);
        let objects: Vec<&str> = record["objects"]
            .as_array()
            .unwrap()
            .iter()
            .map(|o| o.as_str().unwrap())
            .collect();
        assert_eq!(objects.len(), 2);
        for trial in record["trials"].as_array().unwrap() {
            policies.insert(trial["policy"].as_str().unwrap().to_owned());
            failures += usize::from(trial["success"] == false);
            // A test object is never dropped, aimed at or held.
            for field in [&trial["aimed_at"], &trial["held"]] {
                if let Some(name) = field.as_str() {
                    assert!(TRAIN.contains(&name), "{name} in {trial}");
                }
            }
            let rotation = trial["rotation"].as_u64().unwrap();
            let angle = trial["grasp"]["angle_deg"].as_f64().unwrap();
            assert_eq!(
                ((angle / 22.5).round() as u64) % 8,
                rotation,
                "the rotation is the executed angle's bin: {trial}"
            );
            let a = trial["attempt"].as_u64().unwrap();
            let rgb = image::open(store.join(format!("scene_{scene:06}/{a:02}_rgb.png"))).unwrap();
            assert_eq!((rgb.width(), rgb.height()), (128, 128));
        }
        for name in &objects {
            assert!(TRAIN.contains(name) && !TEST.contains(name), "{name}");
        }
    }
    // The untrained model fails often, and --explore 0.5 with mix tries all three kinds.
    assert!(failures > 0, "no failure stored");
    assert!(policies.contains("oracle"), "{policies:?}");
    assert!(
        policies.contains("explore") || policies.contains("model"),
        "{policies:?}"
    );
    let settings = read_json(&store.join("collect.json"));
    assert_eq!(settings["schema"], "graspmap.trials/1");
    assert_eq!(settings["settings"]["objects"], serde_json::json!(TRAIN));
    assert_eq!(
        settings["settings"]["checkpoint"]["sha256"]
            .as_str()
            .unwrap()
            .len(),
        64
    );

    // The same seed on one thread writes the same bytes.
    let args = setup.args("again", "1", &[]);
    assert_ok(&graspmap(
        &args.iter().map(String::as_str).collect::<Vec<_>>(),
    ));
    assert_eq!(store_bytes(&store), store_bytes(&setup.path("again")));

    // --check passes, then names a torn image and exits 2.
    let check = |dir: &str| {
        graspmap(&[
            "--data",
            setup.dir.path().to_str().unwrap(),
            "--split",
            setup.path("split.json").to_str().unwrap(),
            "collect",
            "--check",
            "--out",
            setup.path(dir).to_str().unwrap(),
        ])
    };
    assert_ok(&check("trials"));
    std::fs::write(store.join("scene_000002/00_rgb.png"), b"torn").unwrap();
    let out = check("trials");
    assert_eq!(out.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&out.stdout).contains("scene_000002/00_rgb.png"),
        "{}",
        String::from_utf8_lossy(&out.stdout)
    );

    // Another seed is refused on this store, naming it and the way out.
    let out = setup.collect("again", &["--seed", "6"]);
    assert_user_error(&out, &["again", "other settings", "seed", "--force"]);

    // train --trials records what it was trained on.
    let data = setup.dir.path().to_str().unwrap();
    let out = graspmap(&[
        "--data",
        data,
        "train",
        "--trials",
        setup.path("again").to_str().unwrap(),
        "--no-labels",
        "--epochs",
        "1",
        "--out-dir",
        setup.path("model").to_str().unwrap(),
    ]);
    assert_ok(&out);
    let meta = read_json(&setup.path("model/best.json"));
    let source = &meta["trained_on"]["trials"][0];
    assert_eq!(source["trials"].as_u64().unwrap(), trials);
    assert_eq!(meta["trained_on"]["labels"], 0);
    assert_eq!(meta["config"]["crop"], 64);
}

#[test]
fn shards_merge_into_the_unsharded_store_and_bad_merges_are_refused() {
    let setup = Setup::new();
    assert_ok(&setup.collect("whole", &["--policy", "oracle"]));
    for i in 1..=3 {
        let shard = format!("{i}/3");
        assert_ok(&setup.collect(
            &format!("shard{i}"),
            &["--policy", "oracle", "--shard", &shard],
        ));
    }
    let shard = |i: u32| {
        setup
            .path(&format!("shard{i}"))
            .to_str()
            .unwrap()
            .to_owned()
    };
    let merge = |inputs: &[String], out: &str, extra: &[&str]| {
        let out = setup.path(out).to_str().unwrap().to_owned();
        let mut args: Vec<&str> = vec!["merge", "--out", &out];
        args.extend(inputs.iter().map(String::as_str));
        args.extend_from_slice(extra);
        graspmap(&args)
    };
    assert_ok(&merge(&[shard(2), shard(1), shard(3)], "merged", &[]));
    assert_eq!(
        store_bytes(&setup.path("whole")),
        store_bytes(&setup.path("merged"))
    );

    // Missing, overlapping, and another run's shards are refused, naming what is wrong.
    assert_user_error(
        &merge(&[shard(1), shard(3)], "m1", &[]),
        &["2/3", "missing", "--allow-partial"],
    );
    assert_user_error(
        &merge(&[shard(1), shard(1)], "m2", &[]),
        &["shard1", "1/3", "overlap"],
    );
    assert_ok(&setup.collect(
        "other2",
        &["--policy", "oracle", "--shard", "2/3", "--seed", "9"],
    ));
    let other = setup.path("other2").to_str().unwrap().to_owned();
    assert_user_error(
        &merge(&[shard(1), other, shard(3)], "m3", &[]),
        &["other2", "other settings", "seed"],
    );
    // Another checkpoint is another run too (the model's hash is in the settings).
    assert_ok(&setup.collect("model1", &["--shard", "1/2", "--max-attempts", "1"]));
    std::fs::copy(
        setup.path("affordance/best.safetensors"),
        setup.path("copy.safetensors"),
    )
    .unwrap();
    {
        // Different weights: one value changed.
        let mut bytes = std::fs::read(setup.path("copy.safetensors")).unwrap();
        let last = bytes.len() - 1;
        bytes[last] ^= 1;
        std::fs::write(setup.path("copy.safetensors"), bytes).unwrap();
    }
    let copy = setup.path("copy.safetensors").to_str().unwrap().to_owned();
    assert_ok(&setup.collect(
        "model2",
        &[
            "--shard",
            "2/2",
            "--max-attempts",
            "1",
            "--checkpoint",
            &copy,
        ],
    ));
    let (m1, m2) = (
        setup.path("model1").to_str().unwrap().to_owned(),
        setup.path("model2").to_str().unwrap().to_owned(),
    );
    assert_user_error(&merge(&[m1, m2], "m4", &[]), &["model2", "checkpoint"]);
    // A corrupt shard is named.
    std::fs::write(setup.path("shard3/scene_000002/trials.json"), b"{").unwrap();
    assert_user_error(
        &merge(&[shard(1), shard(2), shard(3)], "m5", &[]),
        &["shard3", "scene_000002"],
    );
    // --allow-partial writes what is there and says so.
    assert_ok(&merge(
        &[shard(1), shard(2)],
        "partial",
        &["--allow-partial"],
    ));
    let settings = read_json(&setup.path("partial/collect.json"));
    assert_eq!(
        settings["missing_shards"],
        serde_json::json!([{"index": 3, "count": 3}])
    );
    // The merge never replaces a store.
    assert_user_error(
        &merge(&[shard(1), shard(2)], "partial", &["--allow-partial"]),
        &["partial", "not empty"],
    );
}

#[test]
fn a_killed_collection_resumes_to_the_same_bytes() {
    let setup = Setup::new();
    assert_ok(&setup.collect("whole", &["--policy", "oracle"]));
    let args = setup.args("killed", "2", &["--policy", "oracle"]);
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_graspmap"))
        .args(&args)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    // Kill it once its first attempt is on disk, as a lost node or `kill -9` would.
    let first = setup.path("killed/scene_000000/trials.json");
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(60);
    while !first.exists() && std::time::Instant::now() < deadline {
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    send_signal(&child, libc::SIGKILL);
    child.wait().unwrap();
    assert!(first.exists(), "the first attempt never landed");
    assert_ne!(
        store_bytes(&setup.path("whole")),
        store_bytes(&setup.path("killed")),
        "killed too late to test resuming"
    );
    let out = setup.collect("killed", &["--policy", "oracle"]);
    assert_ok(&out);
    assert_eq!(
        store_bytes(&setup.path("whole")),
        store_bytes(&setup.path("killed"))
    );
}

/// An eval report's attempts and summary without timings, and its configuration without where
/// its JSON went and the thread count.
fn eval_comparable(report: &serde_json::Value) -> serde_json::Value {
    let mut report = report.clone();
    report["results"]["timing"] = serde_json::Value::Null;
    for run in report["results"]["runs"].as_array_mut().unwrap() {
        for attempt in run["attempts"].as_array_mut().unwrap() {
            attempt["timing"] = serde_json::Value::Null;
        }
    }
    report["config"]["global"]["json"] = serde_json::Value::Null;
    report
}

#[test]
fn eval_shards_merge_into_the_unsharded_report_and_bad_merges_are_refused() {
    let setup = crate::eval::Setup::new();
    let eval = |json: &str, extra: &[&str]| {
        let json = setup.path(json);
        let mut args = vec![
            "eval",
            "--task",
            "train",
            "--seeds",
            "0,7,100",
            "--json",
            json.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        setup.run(&args)
    };
    assert_ok(&eval("whole.json", &[]));
    assert_ok(&eval("s1.json", &["--shard", "1/2"]));
    assert_ok(&eval("s2.json", &["--shard", "2/2"]));
    let s1 = read_json(&setup.path("s1.json"));
    assert_eq!(s1["config"]["shard"], "1/2");
    assert_eq!(s1["results"]["seeds"], serde_json::json!([0, 100]));
    let path = |name: &str| setup.path(name).to_str().unwrap().to_owned();
    let merge = |inputs: &[&str], out: &str, extra: &[&str]| {
        let out = path(out);
        let mut args: Vec<String> = vec!["merge".into(), "--out".into(), out];
        args.extend(inputs.iter().map(|i| path(i)));
        args.extend(extra.iter().map(|s| s.to_string()));
        graspmap(&args.iter().map(String::as_str).collect::<Vec<_>>())
    };
    let out = merge(&["s2.json", "s1.json"], "merged.json", &[]);
    assert_ok(&out);
    assert!(String::from_utf8_lossy(&out.stdout).contains("success rate"));
    let merged = read_json(&setup.path("merged.json"));
    let whole = read_json(&setup.path("whole.json"));
    assert_eq!(eval_comparable(&merged), eval_comparable(&whole));

    // Missing and overlapping shards.
    assert_user_error(
        &merge(&["s1.json"], "m1.json", &[]),
        &["2/2", "missing", "--allow-partial"],
    );
    assert_user_error(
        &merge(&["s1.json", "s1.json"], "m2.json", &[]),
        &["s1.json", "1/2", "overlap"],
    );
    // Another commit.
    let mut other = read_json(&setup.path("s2.json"));
    other["git_commit"] = "0123456789ab".into();
    std::fs::write(setup.path("commit.json"), other.to_string()).unwrap();
    assert_user_error(
        &merge(&["s1.json", "commit.json"], "m3.json", &[]),
        &["commit.json", "commit 0123456789ab"],
    );
    // Another checkpoint: the same shard run with other weights.
    let mut bytes = std::fs::read(setup.path("affordance/best.safetensors")).unwrap();
    let last = bytes.len() - 1;
    bytes[last] ^= 1;
    std::fs::write(setup.path("other.safetensors"), bytes).unwrap();
    assert_ok(&eval(
        "c2.json",
        &["--shard", "2/2", "--checkpoint", &path("other.safetensors")],
    ));
    assert_user_error(
        &merge(&["s1.json", "c2.json"], "m4.json", &[]),
        &["c2.json", "another checkpoint"],
    );
    // Another configuration.
    assert_ok(&eval("n2.json", &["--shard", "2/2", "--verify-top", "50"]));
    assert_user_error(
        &merge(&["s1.json", "n2.json"], "m5.json", &[]),
        &["n2.json", "another configuration", "verify_top"],
    );
    // A corrupt file.
    let text = std::fs::read_to_string(setup.path("s2.json")).unwrap();
    std::fs::write(setup.path("torn.json"), &text[..text.len() / 2]).unwrap();
    assert_user_error(
        &merge(&["s1.json", "torn.json"], "m6.json", &[]),
        &["torn.json", "does not parse"],
    );
    // --allow-partial writes what is there, marked.
    assert_ok(&merge(&["s1.json"], "partial.json", &["--allow-partial"]));
    let partial = read_json(&setup.path("partial.json"));
    assert_eq!(
        partial["config"]["missing_shards"],
        serde_json::json!(["2/2"])
    );
    assert_eq!(partial["results"]["seeds"], serde_json::json!([0, 100]));
}

#[test]
fn improve_collects_with_each_round_s_model_and_a_rerun_continues_without_redoing() {
    let setup = Setup::new();
    let split = setup.path("split.json");
    let improve_with = |extra: &[&str]| {
        let mut args = vec![
            "--data",
            setup.dir.path().to_str().unwrap(),
            "--split",
            split.to_str().unwrap(),
            "--quiet",
            "improve",
        ];
        args.extend_from_slice(extra);
        args.extend_from_slice(&[
            "--scenes",
            "1",
            "--epochs",
            "1",
            "--clutter",
            "2",
            "--max-attempts",
            "2",
        ]);
        graspmap(&args)
    };
    let improve = || {
        graspmap(&[
            "--data",
            setup.dir.path().to_str().unwrap(),
            "--split",
            setup.path("split.json").to_str().unwrap(),
            "--quiet",
            "improve",
            "--rounds",
            "2",
            "--scenes",
            "1",
            "--epochs",
            "1",
            "--clutter",
            "2",
            "--max-attempts",
            "2",
        ])
    };
    let out = improve();
    assert_ok(&out);
    // Its last line's command evaluates the new model as printed.
    let stdout = String::from_utf8_lossy(&out.stdout);
    let hint = stdout
        .lines()
        .find_map(|l| l.split_once("evaluate it with ").map(|(_, c)| c.to_owned()))
        .unwrap_or_else(|| panic!("no command to evaluate with: {stdout}"));
    let words = crate::common::shell_words(&hint);
    assert_eq!(words[0], "graspmap", "{hint}");
    let words: Vec<&str> = words[1..].iter().map(String::as_str).collect();
    assert_ok(&graspmap(&words));
    let summary = read_json(&setup.path("improve/summary.json"));
    let rounds = summary.as_array().unwrap();
    assert_eq!(rounds.len(), 2);
    let round1_model = setup.path("improve/round_01/model/best.safetensors");
    assert_eq!(
        rounds[1]["collected_with"],
        round1_model.to_str().unwrap(),
        "round 2 collects with round 1's model"
    );
    assert_eq!(
        rounds[1]["trials_so_far"].as_u64().unwrap(),
        rounds[0]["trials"].as_u64().unwrap() + rounds[1]["trials"].as_u64().unwrap()
    );
    let meta = read_json(&setup.path("improve/round_02/model/best.json"));
    let trained_on = &meta["trained_on"];
    assert_eq!(trained_on["trials"].as_array().unwrap().len(), 2);
    assert_eq!(trained_on["start"]["path"], round1_model.to_str().unwrap());
    assert_eq!(
        meta["config"]["lr"], 1e-4,
        "a round retrains at a tenth of train's learning rate"
    );
    // A rerun finds every stage done and changes nothing.
    let before = store_bytes(&setup.path("improve/round_02"));
    assert_ok(&improve());
    let after = store_bytes(&setup.path("improve/round_02"));
    let models = |files: &[(String, Vec<u8>)]| -> Vec<(String, Vec<u8>)> {
        files
            .iter()
            .filter(|(name, _)| name.starts_with("model/") || name.starts_with("trials/"))
            .cloned()
            .collect()
    };
    assert_eq!(models(&before), models(&after));
    // Rounds written elsewhere with --out are on the report's page too.
    let elsewhere = setup.path("elsewhere");
    assert_ok(&improve_with(&[
        "--rounds",
        "1",
        "--out",
        elsewhere.to_str().unwrap(),
    ]));
    assert_ok(&graspmap(&[
        "--data",
        setup.dir.path().to_str().unwrap(),
        "report",
    ]));
    let page = std::fs::read_to_string(setup.path("report.html")).unwrap();
    assert!(
        page.contains(&format!("Rounds in {}", elsewhere.display())),
        "the --out rounds are missing from the page"
    );
    assert!(page.contains(&format!("improve {} round 1", elsewhere.display())));
}
