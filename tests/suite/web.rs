//! `label --web` over real HTTP: every endpoint, the guard (Host, Origin, body size, bad
//! requests), 409 on a second confirm, labels stored only on success, and delete-and-renumber
//! through the labels page, with the crash-safety of that delete.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use graspmap::assets::objects::ObjectLibrary;
use graspmap::data::labels::LabelStore;
use graspmap::grasp::PixelGrasp;
use graspmap::policy::oracle;
use graspmap::policy::verify::CheckConfig;
use graspmap::sim::Workcell;
use graspmap::vision::camera::Camera;

use super::common::{send_signal, snapshot};

pub const BIN: &str = env!("CARGO_BIN_EXE_graspmap");

/// A data dir with a split of easy training objects, and a `label --web` serving it.
pub struct WebLabeller {
    pub dir: tempfile::TempDir,
    pub child: Child,
    /// `127.0.0.1:PORT`.
    pub address: String,
    pub train: Vec<String>,
}

impl WebLabeller {
    /// Starts `label --web --port 0` on a fresh data dir with `train` as the training split.
    pub fn start(train: &[&str], extra: &[&str]) -> Self {
        let dir = tempfile::tempdir().unwrap();
        let split = serde_json::json!({ "train": train, "test": [] });
        std::fs::write(dir.path().join("split.json"), split.to_string()).unwrap();
        Self::start_in(dir, train, extra)
    }

    /// Starts it on an existing workspace (`split.json` and `data/` inside `dir`).
    pub fn start_in(dir: tempfile::TempDir, train: &[&str], extra: &[&str]) -> Self {
        let mut child = Command::new(BIN)
            .arg("--data")
            .arg(dir.path().join("data"))
            .arg("--split")
            .arg(dir.path().join("split.json"))
            .args(["label", "--web", "--port", "0"])
            .args(extra)
            .env_remove("GRASPMAP_LOG")
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let mut first = String::new();
        BufReader::new(child.stdout.as_mut().unwrap())
            .read_line(&mut first)
            .unwrap();
        let address = first
            .split("http://")
            .nth(1)
            .and_then(|rest| rest.split('/').next())
            .unwrap_or_else(|| panic!("no address in {first:?}"))
            .to_owned();
        WebLabeller {
            dir,
            child,
            address,
            train: train.iter().map(|s| s.to_string()).collect(),
        }
    }

    pub fn data(&self) -> PathBuf {
        self.dir.path().join("data")
    }

    pub fn store(&self) -> LabelStore {
        LabelStore::new(self.data().join("labels"))
    }

    /// A request with the right Host header.
    pub fn request(&self, method: &str, path: &str, body: Option<&str>) -> (u16, String) {
        let headers = format!("Host: {}\r\n", self.address);
        raw(&self.address, method, path, &headers, body)
    }

    pub fn json(&self, method: &str, path: &str, body: Option<&str>) -> serde_json::Value {
        let (status, text) = self.request(method, path, body);
        assert_eq!(status, 200, "{method} {path}: {text}");
        serde_json::from_str(&text).unwrap()
    }

    pub fn state(&self) -> serde_json::Value {
        self.json("GET", "/api/state", None)
    }

    /// Waits until the state satisfies `ready`.
    pub fn wait_state(&self, ready: impl Fn(&serde_json::Value) -> bool) -> serde_json::Value {
        let start = Instant::now();
        loop {
            let state = self.state();
            if ready(&state) {
                return state;
            }
            assert!(
                start.elapsed() < Duration::from_secs(60),
                "timed out; last state {state}"
            );
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    /// Stops the server as a user would, with Ctrl-C.
    pub fn stop(&mut self) -> std::process::Output {
        send_signal(&self.child, libc::SIGINT);
        let mut stderr = String::new();
        self.child
            .stderr
            .take()
            .unwrap()
            .read_to_string(&mut stderr)
            .unwrap();
        let status = self.child.wait().unwrap();
        std::process::Output {
            status,
            stdout: Vec::new(),
            stderr: stderr.into_bytes(),
        }
    }
}

impl Drop for WebLabeller {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// One HTTP/1.1 request over a fresh connection; the status and body.
pub fn raw(
    address: &str,
    method: &str,
    path: &str,
    headers: &str,
    body: Option<&str>,
) -> (u16, String) {
    let body = body.unwrap_or("");
    let text = format!(
        "{method} {path} HTTP/1.1\r\n{headers}Content-Length: {}\r\nConnection: close\r\n\r\n{body}",
        body.len()
    );
    send(address, text.as_bytes())
}

/// Sends raw bytes and reads the whole response.
pub fn send(address: &str, bytes: &[u8]) -> (u16, String) {
    let mut stream = TcpStream::connect(address).unwrap();
    stream
        .set_read_timeout(Some(Duration::from_secs(10)))
        .unwrap();
    stream.write_all(bytes).unwrap();
    let mut response = Vec::new();
    let _ = stream.read_to_end(&mut response);
    let text = String::from_utf8_lossy(&response).into_owned();
    let status = text
        .split_whitespace()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(0);
    let body = text
        .split_once("\r\n\r\n")
        .map_or("", |(_, b)| b)
        .to_owned();
    (status, body)
}

/// The oracle's click for a round, as the scripted clicker makes it: the round's drop from its
/// seed, planned in the 22.5° steps a person has.
pub fn oracle_click(object: &str, round_seed: u64) -> PixelGrasp {
    let model = ObjectLibrary::bundled().load(object).unwrap();
    let mut cell = Workcell::new(&Default::default()).unwrap();
    cell.drop_objects(std::slice::from_ref(&model), round_seed)
        .unwrap();
    let frame = cell.capture();
    let config = CheckConfig::with_angles(8);
    oracle::plan(&Camera::top_down(), &frame, 1, &config)
        .unwrap()
        .grasp
}

/// The seed of `object`'s round `round` with base seed 0: seed + 100·j + r.
pub fn round_seed(train: &[String], object: &str, round: u64) -> u64 {
    let j = train.iter().position(|t| t == object).unwrap() as u64;
    100 * j + round
}

fn labels_count(store: &LabelStore) -> usize {
    store.load().unwrap().len()
}

/// Clicks, turns to and confirms `grasp` on the round on show; returns the outcome.
fn attempt(web: &WebLabeller, grasp: PixelGrasp) -> serde_json::Value {
    let state = web.wait_state(|s| s["phase"] == "waiting");
    let before = state["last"]["id"].as_u64().unwrap_or(0);
    let click = format!(r#"{{"x": {}, "y": {}}}"#, grasp.u, grasp.v);
    web.json("POST", "/api/click", Some(&click));
    let steps = (grasp.angle_deg / 22.5).round() as i64;
    if steps > 0 {
        let turned = web.json(
            "POST",
            "/api/rotate",
            Some(&format!(r#"{{"steps": {steps}}}"#)),
        );
        assert_eq!(turned["angle"].as_f64().unwrap() as f32, grasp.angle_deg);
    }
    let confirm = format!(r#"{{"round_id": {}}}"#, state["round"]["id"]);
    web.json("POST", "/api/confirm", Some(&confirm));
    let done = web.wait_state(|s| s["last"]["id"].as_u64().unwrap_or(0) > before);
    done["last"].clone()
}

#[test]
fn endpoints_run_rounds_and_store_only_successes() {
    let mut web = WebLabeller::start(&["YcbTennisBall", "YcbFoamBrick"], &["--per-object", "1"]);
    let (status, page) = web.request("GET", "/", None);
    assert_eq!(status, 200);
    assert!(page.contains("<canvas id=\"view\""), "{page}");
    for asset in ["/label.js", "/style.css", "/labels", "/labels.js"] {
        assert_eq!(web.request("GET", asset, None).0, 200, "{asset}");
    }
    let state = web.wait_state(|s| s["phase"] == "waiting");
    assert_eq!(state["round"]["object"], "YcbTennisBall");
    assert_eq!(state["round"]["round"], 0);
    let (status, png) = web.request("GET", "/api/round.png", None);
    assert_eq!(status, 200);
    assert!(png.starts_with("\u{fffd}PNG"), "not a PNG");

    // A grasp in an empty corner of the tote fails, and nothing is stored.
    let miss = attempt(
        &web,
        PixelGrasp {
            u: 20,
            v: 30,
            angle_deg: 45.0,
        },
    );
    assert_eq!(miss["stored"], false, "{miss}");
    assert_ne!(miss["reason"], "success");
    assert!(miss["frames"].as_u64().unwrap() > 10, "{miss}");
    assert_eq!(web.request("GET", "/api/attempt.jpg", None).0, 200);
    assert_eq!(labels_count(&web.store()), 0);

    // The oracle's click for round 1 succeeds and is stored, with its source.
    let state = web.wait_state(|s| s["phase"] == "waiting");
    assert_eq!(state["round"]["round"], 1);
    let grasp = oracle_click("YcbTennisBall", round_seed(&web.train, "YcbTennisBall", 1));
    let hit = attempt(&web, grasp);
    assert_eq!(hit["reason"], "success", "{hit}");
    let labels = web.store().load().unwrap();
    assert_eq!(labels.of("YcbTennisBall").len(), 1);
    assert_eq!(labels.of("YcbTennisBall")[0].x, grasp.u);
    let progress = std::fs::read_to_string(web.data().join("labels/progress.json")).unwrap();
    assert!(progress.contains("\"web\""), "{progress}");

    // The next object's round is on show; the page counts what is done.
    let state = web.wait_state(|s| s["phase"] == "waiting");
    assert_eq!(state["round"]["object"], "YcbFoamBrick");
    assert_eq!(state["dataset"]["labelled"], 1);
    let out = web.stop();
    assert_eq!(out.status.code(), Some(130), "{out:?}");
    // stderr holds only what the stop kept and how to continue: no warning, no progress.
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.starts_with("interrupted by SIGINT: 1 label kept"),
        "{stderr}"
    );
}

#[test]
fn a_second_confirm_while_an_attempt_runs_is_refused_and_nothing_is_written_twice() {
    let web = WebLabeller::start(&["YcbTennisBall"], &["--per-object", "2"]);
    let state = web.wait_state(|s| s["phase"] == "waiting");
    let grasp = oracle_click("YcbTennisBall", 0);
    web.json(
        "POST",
        "/api/click",
        Some(&format!(r#"{{"x": {}, "y": {}}}"#, grasp.u, grasp.v)),
    );
    let steps = (grasp.angle_deg / 22.5).round() as i64;
    web.json(
        "POST",
        "/api/rotate",
        Some(&format!(r#"{{"steps": {steps}}}"#)),
    );
    let confirm = format!(r#"{{"round_id": {}}}"#, state["round"]["id"]);
    assert_eq!(web.request("POST", "/api/confirm", Some(&confirm)).0, 200);
    let (status, body) = web.request("POST", "/api/confirm", Some(&confirm));
    assert_eq!(status, 409, "{body}");
    assert!(body.contains("running"), "{body}");
    let after = web.wait_state(|s| s["last"].is_object());
    assert_eq!(after["last"]["reason"], "success", "{after}");
    // The stale round id of the finished round is refused too, once the next round shows.
    web.wait_state(|s| s["phase"] == "waiting");
    let (status, body) = web.request("POST", "/api/confirm", Some(&confirm));
    assert_eq!(status, 409, "{body}");
    assert_eq!(labels_count(&web.store()), 1);
    assert!(!web
        .store()
        .labels_path()
        .with_file_name("YcbTennisBall_2_rgb.png")
        .exists());
}

#[test]
fn foreign_hosts_origins_big_bodies_and_bad_requests_get_4xx_and_the_server_keeps_running() {
    let web = WebLabeller::start(&["YcbTennisBall"], &["--per-object", "1"]);
    web.wait_state(|s| s["phase"] == "waiting");
    let port = web.address.rsplit(':').next().unwrap().to_owned();
    let host = |h: &str| format!("Host: {h}\r\n");
    let get = |headers: &str| raw(&web.address, "GET", "/api/state", headers, None).0;
    assert_eq!(get(&host(&format!("localhost:{port}"))), 200);
    assert_eq!(get(&host(&format!("127.0.0.1:{port}"))), 200);
    // DNS rebinding: the attacker's name resolves to 127.0.0.1, but the Host header says so.
    assert_eq!(get(&host(&format!("evil.example:{port}"))), 403);
    assert_eq!(get(&host("127.0.0.1:1")), 403);
    assert_eq!(get(""), 403);
    // Another site's page posting to the server.
    let foreign = format!("{}Origin: http://evil.example\r\n", host(&web.address));
    let (status, body) = raw(
        &web.address,
        "POST",
        "/api/rotate",
        &foreign,
        Some(r#"{"steps": 1}"#),
    );
    assert_eq!(status, 403, "{body}");
    let ours = format!("{}Origin: http://{}\r\n", host(&web.address), web.address);
    assert_eq!(
        raw(
            &web.address,
            "POST",
            "/api/rotate",
            &ours,
            Some(r#"{"steps": 1}"#)
        )
        .0,
        200
    );
    let big = "x".repeat(20_000);
    assert_eq!(web.request("POST", "/api/click", Some(&big)).0, 413);
    for (method, path, body, status, needle) in [
        ("POST", "/api/click", "not json", 400, "not valid JSON"),
        (
            "POST",
            "/api/click",
            r#"{"x": 500, "y": 3}"#,
            400,
            "= 500 must be",
        ),
        ("POST", "/api/click", r#"{"x": 5}"#, 400, "= missing"),
        ("POST", "/api/rotate", r#"{"steps": "left"}"#, 400, "steps"),
        // |i64::MIN| does not exist: a check by abs() would wrap and let it through.
        (
            "POST",
            "/api/rotate",
            r#"{"steps": -9223372036854775808}"#,
            400,
            "steps",
        ),
        (
            "POST",
            "/api/confirm",
            r#"{"round_id": 99}"#,
            409,
            "round_id 99",
        ),
        ("GET", "/api/click", "", 405, "does not take GET"),
        ("GET", "/nowhere", "", 404, "/nowhere"),
        (
            "DELETE",
            "/api/labels/YcbTennisBall/1",
            "",
            404,
            "label 1 does not exist",
        ),
        (
            "GET",
            "/api/labels/../etc/1.png",
            "",
            404,
            "not /api/labels",
        ),
    ] {
        let (got, text) = web.request(method, path, Some(body));
        assert_eq!(got, status, "{method} {path} {body}: {text}");
        assert!(text.contains(needle), "{method} {path}: {text}");
        assert_eq!(text.trim().lines().count(), 1, "{text}");
    }
    // Garbage that is not HTTP at all.
    let (status, _) = send(&web.address, b"\x00\x01 nonsense\r\n\r\n");
    assert!((400..500).contains(&status) || status == 0, "{status}");
    assert_eq!(web.state()["phase"], "waiting");
}

/// Labels three tennis-ball grasps through the API (oracle clicks), for the delete tests.
fn labelled(per_object: &str) -> WebLabeller {
    let web = WebLabeller::start(&["YcbTennisBall"], &["--per-object", per_object]);
    let wanted: usize = per_object.parse().unwrap();
    while labels_count(&web.store()) < wanted {
        let state = web.wait_state(|s| s["phase"] == "waiting");
        let round = state["round"]["round"].as_u64().unwrap();
        attempt(&web, oracle_click("YcbTennisBall", round));
    }
    web.wait_state(|s| s["phase"] == "done");
    web
}

#[test]
fn deleting_a_label_renumbers_the_rest_and_the_next_round_refills_it() {
    let mut web = labelled("3");
    let store = web.store();
    let before = store.load().unwrap();
    let image = |k| std::fs::read(store.image_path("YcbTennisBall", k)).unwrap();
    let (second, third) = (image(2), image(3));
    // Its sidecar file (the depth image every label has) moves with it.
    let depth = |k: usize| {
        std::fs::read(
            store
                .image_path("YcbTennisBall", k)
                .with_file_name(format!("YcbTennisBall_{k}_depth.png")),
        )
        .unwrap()
    };
    let third_depth = depth(3);
    let (status, png) = web.request("GET", "/api/labels/YcbTennisBall/2.png", None);
    assert_eq!(status, 200);
    assert!(png.contains("PNG"));
    let list = web.json("GET", "/api/labels", None);
    assert_eq!(list["total"], 3);
    assert_eq!(list["objects"][0]["labels"][1]["source"], "web");

    let after = web.json("DELETE", "/api/labels/YcbTennisBall/2", None);
    assert_eq!(after["total"], 2);
    let labels = store.load().unwrap();
    assert_eq!(labels.of("YcbTennisBall")[0], before.of("YcbTennisBall")[0]);
    assert_eq!(labels.of("YcbTennisBall")[1], before.of("YcbTennisBall")[2]);
    assert_eq!(image(2), third);
    assert_ne!(image(2), second);
    assert!(!store.image_path("YcbTennisBall", 3).exists());
    assert_eq!(depth(2), third_depth);
    assert!(!store
        .image_path("YcbTennisBall", 3)
        .with_file_name("YcbTennisBall_3_depth.png")
        .exists());

    // The labelling loop wakes up and refills the gap with a new round.
    let state = web.wait_state(|s| s["phase"] == "waiting");
    let round = state["round"]["round"].as_u64().unwrap();
    assert!(round >= 3, "{state}");
    let refill = attempt(&web, oracle_click("YcbTennisBall", round));
    assert_eq!(refill["reason"], "success", "{refill}");
    web.wait_state(|s| s["phase"] == "done");
    assert_eq!(store.load().unwrap().of("YcbTennisBall").len(), 3);
    let data = web.data();
    let out = web.stop();
    assert_eq!(out.status.code(), Some(0), "{out:?}");
    let check = Command::new(BIN)
        .arg("--data")
        .arg(&data)
        .args(["label", "--check"])
        .output()
        .unwrap();
    assert!(check.status.success(), "{check:?}");
}

#[test]
#[cfg_attr(
    not(feature = "fault-injection"),
    ignore = "injects faults: needs --features fault-injection, which ./test.sh turns on"
)]
fn a_delete_killed_at_any_step_leaves_the_old_or_the_new_dataset_and_both_pass_check() {
    let mut web = labelled("3");
    let data = web.data();
    web.stop();
    let labels_dir = data.join("labels");
    let old = snapshot(&labels_dir);
    let delete = |env: Option<&str>| {
        let mut command = Command::new(BIN);
        command
            .arg("--data")
            .arg(&data)
            .args(["label", "--delete", "YcbTennisBall:1"]);
        if let Some(step) = env {
            command.env("GRASPMAP_TEST_ABORT_DELETE", step);
        }
        command.output().unwrap()
    };
    let check = || {
        Command::new(BIN)
            .arg("--data")
            .arg(&data)
            .args(["label", "--check"])
            .output()
            .unwrap()
    };
    // The new dataset, made once without a kill, then put back.
    let backup = tempfile::tempdir().unwrap();
    for (name, bytes) in &old {
        std::fs::write(backup.path().join(name), bytes).unwrap();
    }
    assert!(delete(None).status.success());
    let new = snapshot(&labels_dir);
    assert_eq!(
        new.iter().filter(|(n, _)| n.ends_with("_rgb.png")).count(),
        2
    );
    for step in 1..=5 {
        std::fs::remove_dir_all(&labels_dir).unwrap();
        std::fs::create_dir(&labels_dir).unwrap();
        for (name, bytes) in &old {
            std::fs::write(labels_dir.join(name), bytes).unwrap();
        }
        let out = delete(Some(&step.to_string()));
        assert!(!out.status.success(), "step {step} did not abort");
        let now = snapshot(&labels_dir);
        let expected = if step == 5 { &new } else { &old };
        assert!(
            now == *expected,
            "after a kill at step {step}: neither the old nor the new dataset"
        );
        assert!(
            check().status.success(),
            "--check after a kill at step {step}: {:?}",
            check()
        );
    }
    // The next writer clears the staging directory a kill left.
    assert!(delete(None).status.success());
    assert!(!data.join(".labels.next").exists());
}

#[test]
fn a_scripted_dataset_is_topped_up_by_hand_and_each_label_keeps_its_source() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("split.json"),
        r#"{"train": ["YcbTennisBall"], "test": []}"#,
    )
    .unwrap();
    let label = |args: &[&str]| {
        Command::new(BIN)
            .arg("--data")
            .arg(dir.path().join("data"))
            .arg("--split")
            .arg(dir.path().join("split.json"))
            .arg("label")
            .args(args)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap()
    };
    let scripted = label(&["--per-object", "1"]).wait_with_output().unwrap();
    assert!(scripted.status.success(), "{scripted:?}");
    let progress_path = dir.path().join("data/labels/progress.json");
    let progress: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&progress_path).unwrap()).unwrap();
    let rounds = progress["rounds"][0]["rounds"].as_u64().unwrap();
    // The person's click for the next round, typed at the prompt.
    let grasp = oracle_click("YcbTennisBall", rounds);
    let mut by_hand = label(&["--per-object", "2", "--interactive"]);
    let mut keys = format!("{} {}\n", grasp.u, grasp.v);
    for _ in 0..(grasp.angle_deg / 22.5).round() as usize {
        keys.push_str("d\n");
    }
    keys.push_str("q\n");
    by_hand
        .stdin
        .take()
        .unwrap()
        .write_all(keys.as_bytes())
        .unwrap();
    let out = by_hand.wait_with_output().unwrap();
    assert!(out.status.success(), "{out:?}");
    let progress: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&progress_path).unwrap()).unwrap();
    assert_eq!(progress["schema"], "graspmap.label-progress/2");
    assert_eq!(
        progress["rounds"][0]["sources"],
        serde_json::json!(["scripted", "interactive"])
    );
    // Another seed is still refused: it would change every round's drop.
    let other = label(&["--per-object", "3", "--seed", "7"])
        .wait_with_output()
        .unwrap();
    assert_eq!(other.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&other.stderr).contains("--seed 0"));
}

#[test]
fn delete_names_what_is_wrong_with_its_argument() {
    let dir = tempfile::tempdir().unwrap();
    let run = |value: &str| {
        Command::new(BIN)
            .arg("--data")
            .arg(dir.path())
            .args(["label", "--delete", value])
            .output()
            .unwrap()
    };
    for (value, needle) in [
        ("YcbHammer", "is not OBJECT:K"),
        ("YcbHammer:0", "K counts from 1"),
        ("YcbHammer:two", "is not OBJECT:K"),
        ("YcbHammer:3", "YcbHammer has 0 labels"),
    ] {
        let out = run(value);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{value}: {stderr}");
        assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
        assert!(stderr.contains(needle), "{value}: {stderr}");
    }
}

#[test]
fn report_serve_shows_the_report_and_the_labels_and_deletes_only_under_the_lock() {
    let mut web = labelled("2");
    let data = web.data();
    web.stop();
    let mut child = Command::new(BIN)
        .arg("--data")
        .arg(&data)
        .args(["report", "--serve", "--port", "0"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut first = String::new();
    let mut stdout = BufReader::new(child.stdout.take().unwrap());
    while !first.contains("http://") {
        first.clear();
        assert!(
            stdout.read_line(&mut first).unwrap() > 0,
            "no address printed"
        );
    }
    let address = first
        .split("http://")
        .nth(1)
        .unwrap()
        .split('/')
        .next()
        .unwrap()
        .to_owned();
    let get = |path: &str| raw(&address, "GET", path, &format!("Host: {address}\r\n"), None);
    let (status, page) = get("/report");
    assert_eq!(status, 200);
    assert!(page.contains("graspmap run report"), "{page}");
    let link = page
        .split("src=\"")
        .nth(1)
        .and_then(|rest| rest.split('"').next())
        .expect("the report shows an image");
    assert_eq!(get(&format!("/{link}")).0, 200, "{link}");
    assert_eq!(get("/report_files/../labels/labels.json").0, 404);
    assert_eq!(get("/").0, 200);
    assert_eq!(get("/labels").0, 200);
    // A page the user wrote where the report goes is theirs: /report leaves it as it is.
    let page = data.join("report.html");
    std::fs::write(&page, "<p>my notes</p>").unwrap();
    let (status, text) = get("/report");
    assert_eq!(status, 409, "{text}");
    assert!(
        text.contains("report.html") && text.contains("--force"),
        "{text}"
    );
    assert_eq!(std::fs::read_to_string(&page).unwrap(), "<p>my notes</p>");
    std::fs::remove_file(&page).unwrap();
    assert_eq!(get("/report").0, 200);
    let listed: serde_json::Value = serde_json::from_str(&get("/api/labels").1).unwrap();
    assert_eq!(listed["total"], 2);
    // A labeller holding the store: the delete is refused, naming the lock.
    let lock = graspmap::data::lock::StoreLock::acquire(&data.join("labels"), "label").unwrap();
    let delete = |path: &str| {
        raw(
            &address,
            "DELETE",
            path,
            &format!("Host: {address}\r\n"),
            None,
        )
    };
    let (status, body) = delete("/api/labels/YcbTennisBall/1");
    assert_eq!(status, 409, "{body}");
    assert!(body.contains(".lock"), "{body}");
    drop(lock);
    let (status, body) = delete("/api/labels/YcbTennisBall/1");
    assert_eq!(status, 200, "{body}");
    assert_eq!(
        LabelStore::new(data.join("labels")).load().unwrap().len(),
        1
    );
    send_signal(&child, libc::SIGINT);
    // Stopped by Ctrl-C, as `label --web` is: 128 + SIGINT.
    assert_eq!(child.wait().unwrap().code(), Some(130));
}

#[test]
fn another_host_warns_and_still_refuses_host_names_that_are_not_ours() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("split.json"),
        r#"{"train": ["YcbTennisBall"], "test": []}"#,
    )
    .unwrap();
    let mut web = WebLabeller::start_in(
        dir,
        &["YcbTennisBall"],
        &["--per-object", "1", "--host", "0.0.0.0"],
    );
    let port = web.address.rsplit(':').next().unwrap().to_owned();
    let get = |host: &str| {
        raw(
            &web.address,
            "GET",
            "/api/state",
            &format!("Host: {host}\r\n"),
            None,
        )
        .0
    };
    assert_eq!(get(&format!("127.0.0.1:{port}")), 200);
    assert_eq!(get(&format!("localhost:{port}")), 200);
    // Reached over the network by its address: an IP literal cannot be a rebinding name.
    assert_eq!(get(&format!("192.0.2.7:{port}")), 200);
    assert_eq!(get(&format!("evil.example:{port}")), 403);
    assert_eq!(get("192.0.2.7:1"), 403);
    let out = web.stop();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("other machines on the network") && stderr.contains("--host 127.0.0.1"),
        "{stderr}"
    );
}
