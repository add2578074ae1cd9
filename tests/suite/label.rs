//! `graspmap label` end to end: the reference format, resuming after a kill, `--check`, file-driven and interactive clicks.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::Duration;

use graspmap::data::labels::{LabelStore, Labels};

use crate::common::poll_until;

const BIN: &str = env!("CARGO_BIN_EXE_graspmap");

fn fixture() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/reference-labels")
}

/// A data dir with a split of two easy training objects, so runs take a second or two.
struct Workspace {
    dir: tempfile::TempDir,
}

impl Workspace {
    fn new() -> Self {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("split.json"),
            r#"{"train": ["YcbTennisBall", "YcbFoamBrick"], "test": []}"#,
        )
        .unwrap();
        Self { dir }
    }

    fn data(&self) -> PathBuf {
        self.dir.path().join("data")
    }

    fn labels(&self) -> PathBuf {
        self.data().join("labels")
    }

    fn command(&self, args: &[&str]) -> Command {
        let mut command = Command::new(BIN);
        command
            .arg("--data")
            .arg(self.data())
            .arg("--split")
            .arg(self.dir.path().join("split.json"))
            .arg("label")
            .args(args)
            .env_remove("GRASPMAP_LOG");
        command
    }

    fn run(&self, args: &[&str]) -> Output {
        self.command(args).output().unwrap()
    }

    /// Every file of the labels dir but the writer's lock, by name, with its bytes.
    fn snapshot(&self) -> Vec<(String, Vec<u8>)> {
        super::common::snapshot(&self.labels())
    }
}

fn assert_ok(out: &Output) {
    assert!(
        out.status.success(),
        "stdout: {}\nstderr: {}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

fn assert_user_error(out: &Output, needle: &str) {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "stderr: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    assert!(stderr.contains(needle), "{needle:?} missing from {stderr}");
}

#[test]
fn the_reference_fixture_loads_and_round_trips() {
    let store = LabelStore::new(fixture());
    let labels = store.load().unwrap();
    assert_eq!(labels.len(), 4);
    assert_eq!(labels.of("YcbHammer")[1].angle, 112.5);
    assert_eq!(
        (
            labels.of("YcbTomatoSoupCan")[0].x,
            labels.of("YcbTomatoSoupCan")[0].y
        ),
        (64, 58)
    );
    let known = ["YcbHammer".to_owned(), "YcbTomatoSoupCan".to_owned()];
    assert_eq!(store.check(&known), Vec::<String>::new());
    // Written back, it is byte for byte the reference tool's file (indent 4, float angles).
    let original = std::fs::read_to_string(store.labels_path()).unwrap();
    assert_eq!(labels.to_json().trim_end(), original.trim_end());
    assert_eq!(
        Labels::parse(&labels.to_json(), Path::new("x")).unwrap(),
        labels
    );
}

#[test]
fn no_json_report_replaces_the_labelling_state() {
    let ws = Workspace::new();
    assert_ok(&ws.run(&["--per-object", "1"]));
    let before = ws.snapshot();
    for file in ["progress.json", "labels.json"] {
        let target = ws.labels().join(file);
        let out = Command::new(BIN)
            .arg("--data")
            .arg(ws.data())
            .arg("--json")
            .arg(&target)
            .args(["eval", "--task", "test", "--policy", "random"])
            .output()
            .unwrap();
        assert_user_error(&out, file);
        // The same file outside the data directory is still recognised as state.
        let copy = ws.dir.path().join(file);
        std::fs::copy(&target, &copy).unwrap();
        let out = Command::new(BIN)
            .arg("--json")
            .arg(&copy)
            .args(["scene", "--objects", "YcbPear", "--force", "--out"])
            .arg(ws.dir.path().join("scene.png"))
            .output()
            .unwrap();
        assert_user_error(&out, "which graspmap reads");
        assert_eq!(
            std::fs::read(&copy).unwrap(),
            std::fs::read(&target).unwrap()
        );
    }
    assert_eq!(ws.snapshot(), before);
    assert_ok(&ws.run(&["--check"]));
}

#[test]
fn the_same_seed_gives_byte_identical_datasets_whatever_the_thread_count() {
    let a = Workspace::new();
    let b = Workspace::new();
    // Noisy clicks miss now and then, and two threads then share out a second wave of rounds.
    let noisy = ["--per-object", "3", "--click-noise-px", "4"];
    let two = a.run(&[&noisy[..], &["--threads", "2", "--json", "-"]].concat());
    assert_ok(&two);
    assert_ok(&b.run(&[&noisy[..], &["--threads", "1"]].concat()));
    let report: serde_json::Value = serde_json::from_slice(&two.stdout).unwrap();
    let rounds: Vec<(String, u64)> = report["results"]["objects"]
        .as_array()
        .unwrap()
        .iter()
        .map(|o| {
            (
                o["object"].as_str().unwrap().to_owned(),
                o["rounds"].as_u64().unwrap(),
            )
        })
        .collect();
    assert!(
        rounds.iter().any(|(_, r)| *r > 3),
        "this test needs a missed round: {rounds:?}"
    );
    let snapshot = a.snapshot();
    assert_eq!(snapshot, b.snapshot());
    let labels = LabelStore::new(a.labels()).load().unwrap();
    assert_eq!(labels.of("YcbTennisBall").len(), 3);
    assert_eq!(labels.of("YcbFoamBrick").len(), 3);
    // Another seed, other scenes.
    let c = Workspace::new();
    assert_ok(&c.run(&[&noisy[..], &["--seed", "7"]].concat()));
    assert_ne!(snapshot, c.snapshot());
}

#[test]
fn a_run_killed_at_any_point_resumes_to_the_same_dataset() {
    let reference = Workspace::new();
    assert_ok(&reference.run(&["--per-object", "4"]));
    let expected = reference.snapshot();
    let wanted = 8; // 4 labels of each of the 2 training objects
                    // Killed once the run has shown it got that far: its progress file written (before any
                    // label), then 1, 3 and 6 labels stored. Polled, not slept, so a slow machine kills at the
                    // same points as a fast one.
    for labelled in [0, 1, 3, 6] {
        let ws = Workspace::new();
        let mut child = ws
            .command(&["--per-object", "4", "--threads", "1"])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let store = LabelStore::new(ws.labels());
        let what = format!("{labelled} labels");
        poll_until(&mut child, &what, Duration::from_secs(120), || {
            let progress = ws.labels().join("progress.json").exists();
            let have = store.load().unwrap().len();
            match progress && have >= labelled {
                true => Ok(()),
                false => Err(format!("{have} labels")),
            }
        });
        child.kill().unwrap();
        let status = child.wait().unwrap();
        // The kill landed mid-run: the process died of it, with the dataset unfinished.
        use std::os::unix::process::ExitStatusExt;
        assert_eq!(
            status.signal(),
            Some(libc::SIGKILL),
            "killed after {labelled} labels"
        );
        let kept = store.load().unwrap().len();
        assert!(
            (labelled..wanted).contains(&kept),
            "killed after {labelled} labels, {kept} kept"
        );
        // Whatever was written is a valid dataset (before the first label, there is none).
        if ws.labels().join("labels.json").exists() {
            let known = ["YcbTennisBall".to_owned(), "YcbFoamBrick".to_owned()];
            let problems = store.check(&known);
            let real: Vec<_> = problems
                .iter()
                .filter(|p| !p.contains("extra image"))
                .collect();
            assert!(
                real.is_empty(),
                "after a kill at {labelled} labels: {problems:?}"
            );
        }
        assert_ok(&ws.run(&["--per-object", "4"]));
        assert_eq!(ws.snapshot(), expected, "killed at {labelled} labels");
    }
}

#[test]
fn resuming_asks_for_the_same_settings() {
    let ws = Workspace::new();
    assert_ok(&ws.run(&["--per-object", "1"]));
    assert_user_error(&ws.run(&["--per-object", "2", "--seed", "3"]), "--seed 0");
    // --force starts over with the new settings.
    assert_ok(&ws.run(&["--per-object", "1", "--seed", "3", "--force"]));
}

#[test]
fn warnings_carry_no_colour_codes_when_stderr_is_not_a_terminal() {
    let ws = Workspace::new();
    let labels = ws.labels();
    std::fs::create_dir_all(&labels).unwrap();
    for entry in std::fs::read_dir(fixture()).unwrap().flatten() {
        std::fs::copy(entry.path(), labels.join(entry.file_name())).unwrap();
    }
    let split = ws.dir.path().join("fixture_split.json");
    std::fs::write(
        &split,
        r#"{"train": ["YcbHammer", "YcbTomatoSoupCan"], "test": []}"#,
    )
    .unwrap();
    // The fixture has its 2 labels per object and no progress file: a warning, no work.
    let out = Command::new(BIN)
        .arg("--data")
        .arg(ws.data())
        .arg("--split")
        .arg(&split)
        .args(["label", "--per-object", "2"])
        .env_remove("GRASPMAP_LOG")
        .output()
        .unwrap();
    assert_ok(&out);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("WARN") && stderr.contains("no progress file"),
        "{stderr}"
    );
    assert!(
        !stderr.contains('\x1b'),
        "colour codes in a file: {stderr:?}"
    );
}

#[test]
fn check_reports_each_kind_of_corruption() {
    let ws = Workspace::new();
    let labels = ws.labels();
    std::fs::create_dir_all(&labels).unwrap();
    for entry in std::fs::read_dir(fixture()).unwrap().flatten() {
        std::fs::copy(entry.path(), labels.join(entry.file_name())).unwrap();
    }
    assert_ok(&ws.run(&["--check"]));

    std::fs::remove_file(labels.join("YcbHammer_2_rgb.png")).unwrap();
    image::RgbImage::new(128, 128)
        .save(labels.join("YcbHammer_7_rgb.png"))
        .unwrap();
    image::RgbImage::new(64, 64)
        .save(labels.join("YcbTomatoSoupCan_1_rgb.png"))
        .unwrap();
    let text = std::fs::read_to_string(labels.join("labels.json"))
        .unwrap()
        .replacen("75,", "200,", 1)
        .replace("YcbTomatoSoupCan", "YcbUnicorn");
    std::fs::write(labels.join("labels.json"), text).unwrap();
    // The renamed object's images are now extra files, and its own images are missing.
    let out = ws.run(&["--check"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(2));
    for needle in [
        "YcbHammer_2_rgb.png: missing image",
        "YcbHammer_7_rgb.png: extra image",
        "x = 200",
        "unknown object 'YcbUnicorn'",
        "YcbTomatoSoupCan_1_rgb.png: extra image",
    ] {
        assert!(
            stdout.contains(needle),
            "{needle:?} not reported:\n{stdout}"
        );
    }

    // A wrong image size is reported for a listed image.
    let ws = Workspace::new();
    let labels = ws.labels();
    std::fs::create_dir_all(&labels).unwrap();
    for entry in std::fs::read_dir(fixture()).unwrap().flatten() {
        std::fs::copy(entry.path(), labels.join(entry.file_name())).unwrap();
    }
    image::RgbImage::new(64, 64)
        .save(labels.join("YcbTomatoSoupCan_2_rgb.png"))
        .unwrap();
    let out = ws.run(&["--check"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stdout).contains("image is 64×64, expected 128×128"));
}

#[test]
fn file_driven_clicks_reproduce_the_labels_they_describe() {
    // Seed 1: every scripted round of it succeeds (with seed 0 one foam-brick round misses).
    let scripted = Workspace::new();
    let args = ["--per-object", "2", "--seed", "1", "--json", "-"];
    assert_ok(&scripted.run(&args));
    let labels = LabelStore::new(scripted.labels()).load().unwrap();
    let report: serde_json::Value = serde_json::from_slice(&scripted.run(&args).stdout).unwrap();
    for object in report["results"]["objects"].as_array().unwrap() {
        assert_eq!(
            object["rounds"], 2,
            "this test needs every scripted round to succeed"
        );
    }
    let clicks: Vec<serde_json::Value> = labels
        .iter()
        .flat_map(|(object, list)| {
            list.iter()
                .map(move |l| serde_json::json!({"object": object, "x": l.x, "y": l.y, "angle": l.angle}))
        })
        .collect();
    let replay = Workspace::new();
    let clicks_path = replay.dir.path().join("clicks.json");
    std::fs::write(&clicks_path, serde_json::to_string(&clicks).unwrap()).unwrap();
    let out = replay.run(&[
        "--per-object",
        "2",
        "--seed",
        "1",
        "--clicks",
        clicks_path.to_str().unwrap(),
    ]);
    assert_ok(&out);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("YcbFoamBrick round 1 click"),
        "each click is reported: {stdout}"
    );
    let files = |ws: &Workspace| {
        ws.snapshot()
            .into_iter()
            .filter(|(name, _)| name != "progress.json")
            .collect::<Vec<_>>()
    };
    assert_eq!(files(&replay), files(&scripted));
}

#[test]
fn bad_clicks_files_fail_before_any_simulation() {
    let ws = Workspace::new();
    let path = ws.dir.path().join("clicks.json");
    let good = r#"{"object": "YcbTennisBall", "x": 64, "y": 64, "angle": 0}"#;
    for (text, needle) in [
        (
            r#"[{"object": "YcbUnicorn", "x": 1, "y": 2, "angle": 0}]"#.to_owned(),
            "unknown object 'YcbUnicorn'",
        ),
        (
            r#"[{"object": "YcbTennisBall", "x": 128, "y": 2, "angle": 0}]"#.to_owned(),
            "\"x\" = 128",
        ),
        (
            r#"[{"object": "YcbTennisBall", "x": 1, "y": "top", "angle": 0}]"#.to_owned(),
            "\"y\" = \"top\"",
        ),
        (format!("[{good}]"), "clicks for YcbTennisBall"),
        ("{not json".to_owned(), "not valid JSON"),
    ] {
        std::fs::write(&path, text).unwrap();
        let out = ws.run(&["--per-object", "2", "--clicks", path.to_str().unwrap()]);
        assert_user_error(&out, needle);
        assert!(!ws.labels().join("labels.json").exists());
    }
}

#[test]
fn interactive_clicks_come_from_stdin() {
    let ws = Workspace::new();
    // Learn a click that works for round 0 of the first object from a scripted run.
    let scripted = Workspace::new();
    assert_ok(&scripted.run(&["--per-object", "1"]));
    let label = LabelStore::new(scripted.labels())
        .load()
        .unwrap()
        .of("YcbTennisBall")[0];
    let preview = ws.dir.path().join("preview.png");
    let turns = (label.angle / 22.5).round() as usize;
    let mut script = format!("{} {}\n", label.x, label.y);
    script.push_str(&"d\n".repeat(turns));
    script.push_str("q\n");
    let mut child = ws
        .command(&[
            "--per-object",
            "1",
            "--interactive",
            "--preview",
            preview.to_str().unwrap(),
        ])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    child
        .stdin
        .take()
        .unwrap()
        .write_all(script.as_bytes())
        .unwrap();
    let out = child.wait_with_output().unwrap();
    // The foam brick never gets its click: stdin ends, and the run stops with what it has.
    assert_user_error(&out, "stdin closed");
    let got = LabelStore::new(ws.labels()).load().unwrap();
    assert_eq!(got.of("YcbTennisBall"), &[label]);
    let preview_image = image::open(&preview).unwrap();
    assert_eq!((preview_image.width(), preview_image.height()), (512, 512));
}

/// Waits until `path` exists (a child has reached some point), at most 60 s.
fn wait_for(path: &Path) {
    let start = std::time::Instant::now();
    while !path.exists() {
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "{} never appeared",
            path.display()
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn a_second_labeller_is_refused_at_once_and_a_killed_ones_lock_never_blocks() {
    let ws = Workspace::new();
    // A person labelling interactively holds the store while the prompt waits.
    let mut person = ws
        .command(&["--interactive"])
        .stdin(Stdio::piped())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    wait_for(&ws.labels().join("preview.png"));
    let start = std::time::Instant::now();
    let out = ws.run(&["--per-object", "1"]);
    assert!(
        start.elapsed() < Duration::from_secs(10),
        "the second writer waited"
    );
    assert_user_error(&out, ".lock");
    assert_user_error(&out, &format!("process {}", person.id()));
    // Killed with SIGKILL, the holder cannot clean up; its lock goes with it all the same.
    person.kill().unwrap();
    person.wait().unwrap();
    assert_ok(&ws.run(&["--per-object", "1"]));
}

#[test]
fn ctrl_c_stops_after_the_current_round_and_the_rerun_finishes_the_same_dataset() {
    let reference = Workspace::new();
    assert_ok(&reference.run(&["--per-object", "3"]));
    let ws = Workspace::new();
    let child = ws
        .command(&["--per-object", "3", "--threads", "1"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    wait_for(&ws.labels().join("labels.json"));
    crate::common::send_signal(&child, libc::SIGINT);
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "stderr: {stderr}");
    assert!(stderr.contains("interrupted by SIGINT"), "{stderr}");
    assert!(stderr.contains("rerun the same command"), "{stderr}");
    assert_ok(&ws.run(&["--check"]));
    assert_ok(&ws.run(&["--per-object", "3"]));
    assert_eq!(ws.snapshot(), reference.snapshot());
}

#[test]
#[cfg_attr(
    not(feature = "fault-injection"),
    ignore = "injects faults: needs --features fault-injection, which ./test.sh turns on"
)]
fn a_full_disk_at_any_write_of_a_round_fails_clearly_and_the_rerun_resumes() {
    let reference = Workspace::new();
    assert_ok(&reference.run(&["--per-object", "1", "--threads", "1"]));
    let expected = reference.snapshot();
    // One successful round writes the depth image, the image, labels.json and progress.json;
    // failed rounds write progress.json. Fail each of the first writes in turn.
    for n in 1..=9 {
        let ws = Workspace::new();
        let out = ws
            .command(&["--per-object", "1", "--threads", "1"])
            .env("GRASPMAP_TEST_FAIL_WRITE", n.to_string())
            .output()
            .unwrap();
        if out.status.success() {
            // Fewer writes than n: the whole run fit before the fault.
            assert_eq!(ws.snapshot(), expected, "write {n}");
            continue;
        }
        assert_user_error(&out, "No space left on device");
        assert_user_error(&out, "labels");
        if ws.labels().join("labels.json").exists() {
            assert_ok(&ws.run(&["--check"]));
        }
        assert_ok(&ws.run(&["--per-object", "1", "--threads", "1"]));
        let differing: Vec<String> = ws
            .snapshot()
            .into_iter()
            .zip(&expected)
            .filter(|(a, b)| a != *b)
            .map(|(a, _)| format!("{}: {}", a.0, String::from_utf8_lossy(&a.1)))
            .collect();
        assert!(
            differing.is_empty(),
            "after a full disk at write {n}: {differing:?}"
        );
        assert_eq!(ws.snapshot(), expected, "after a full disk at write {n}");
    }
}

/// A tiny tmpfs mounted for one test, unmounted when dropped.
struct TinyDisk {
    dir: tempfile::TempDir,
}

impl TinyDisk {
    /// Mounts `size` of tmpfs, or says why it cannot (not root, no mount(8), a sandbox).
    fn mount(size: &str) -> Result<Self, String> {
        let dir = tempfile::tempdir().map_err(|e| e.to_string())?;
        let out = Command::new("mount")
            .args(["-t", "tmpfs", "-o", &format!("size={size}"), "tmpfs"])
            .arg(dir.path())
            .output()
            .map_err(|e| e.to_string())?;
        if !out.status.success() {
            return Err(String::from_utf8_lossy(&out.stderr).trim().to_owned());
        }
        Ok(Self { dir })
    }
}

impl Drop for TinyDisk {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(self.dir.path()).status();
    }
}

#[test]
fn a_real_full_disk_is_a_one_line_error_and_leaves_a_valid_dataset() {
    // A real full disk needs a mount: as root (CI and ./test.sh run as root), with mount(8).
    // Where that cannot be, the test fails with the fix rather than passing untested; a
    // machine that knowingly lacks it skips it, visibly, with GRASPMAP_TEST_NO_TMPFS=1.
    if std::env::var_os("GRASPMAP_TEST_NO_TMPFS").is_some() {
        eprintln!("SKIPPED: the real full-disk test (GRASPMAP_TEST_NO_TMPFS is set)");
        return;
    }
    let disk = TinyDisk::mount("48k").unwrap_or_else(|why| {
        panic!(
            "cannot mount a tmpfs for the real full-disk test ({why}): run the tests as root \
             (CAP_SYS_ADMIN, outside a sandbox that forbids mounts) with mount(8) from \
             util-linux installed (apt-get install mount), or set GRASPMAP_TEST_NO_TMPFS=1 to \
             skip it knowingly"
        )
    });
    let data = disk.dir.path().join("data");
    let split = disk.dir.path().join("split.json");
    std::fs::write(
        &split,
        r#"{"train": ["YcbTennisBall", "YcbFoamBrick"], "test": []}"#,
    )
    .unwrap();
    // Each label image is 5 to 10 kB: the disk fills a few labels in.
    let out = Command::new(BIN)
        .arg("--data")
        .arg(&data)
        .arg("--split")
        .arg(&split)
        .args(["label", "--per-object", "12", "--threads", "1"])
        .env_remove("GRASPMAP_LOG")
        .output()
        .unwrap();
    assert_user_error(&out, "No space left on device");
    let store = LabelStore::new(data.join("labels"));
    let known = ["YcbTennisBall".to_owned(), "YcbFoamBrick".to_owned()];
    assert_eq!(store.check(&known), Vec::<String>::new());
    assert!(
        !store.load().unwrap().is_empty(),
        "the disk filled before any label"
    );
}
