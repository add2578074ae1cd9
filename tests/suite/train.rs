//! `graspmap train` end to end on the small reference fixture: loss goes down, checkpoints round-trip, resume is exact, bad inputs are clear errors.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use graspmap::model::checkpoint::{read_checkpoint, save_checkpoint, CheckpointMeta};
use graspmap::model::config::{Plateau, TrainConfig};
use graspmap::model::unet::MiniUNet;
use tch::nn;

use crate::common::{assert_ok, assert_user_error, graspmap};

const BIN: &str = env!("CARGO_BIN_EXE_graspmap");

/// A data dir holding a copy of the reference fixture's four labels.
fn data_dir() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let labels = dir.path().join("labels");
    std::fs::create_dir_all(&labels).unwrap();
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/reference-labels");
    for entry in std::fs::read_dir(fixture).unwrap().flatten() {
        std::fs::copy(entry.path(), labels.join(entry.file_name())).unwrap();
    }
    dir
}

fn train(data: &Path, args: &[&str]) -> Output {
    train_in(data, "fp32", args)
}

fn train_in(data: &Path, precision: &str, args: &[&str]) -> Output {
    train_command(data, precision, args).output().unwrap()
}

/// `graspmap --data DATA --threads 2 train --batch-size 2 --precision PRECISION ARGS`.
fn train_command(data: &Path, precision: &str, args: &[&str]) -> Command {
    let mut command = Command::new(BIN);
    command
        .arg("--data")
        .arg(data)
        .args(["--threads", "2", "train", "--batch-size", "2"])
        .args(["--precision", precision])
        .args(args)
        .env_remove("GRASPMAP_LOG");
    command
}

fn history(data: &Path, name: &str) -> CheckpointMeta {
    read_checkpoint(&data.join("affordance"), name).unwrap().1
}

#[test]
fn three_epochs_lower_the_loss_and_write_every_artefact() {
    let data = data_dir();
    assert_ok(&train(data.path(), &["--epochs", "3"]));
    let meta = history(data.path(), "last");
    assert_eq!(meta.epoch, 3);
    let losses: Vec<f64> = meta.history.iter().map(|r| r.train_loss).collect();
    assert!(
        losses[2] < losses[0],
        "training loss did not go down: {losses:?}"
    );
    let out: PathBuf = data.path().join("affordance");
    for file in [
        "best.safetensors",
        "best.json",
        "last.safetensors",
        "last.json",
        "losses.csv",
    ] {
        assert!(out.join(file).is_file(), "{file} missing");
    }
    for epoch in 1..=3 {
        let vis = image::open(out.join(format!("training_vis/{epoch:03}.png"))).unwrap();
        // Three 256 px panels (the label, the prediction, the target) over a colour bar.
        assert_eq!((vis.width(), vis.height()), (768, 278));
    }
    let curve = image::open(out.join("losses.png")).unwrap();
    assert_eq!((curve.width(), curve.height()), (800, 500));
    let csv = std::fs::read_to_string(out.join("losses.csv")).unwrap();
    assert_eq!(csv.lines().count(), 4, "{csv}");
    let best = history(data.path(), "best");
    let lowest = meta
        .history
        .iter()
        .map(|r| r.val_loss)
        .fold(f64::INFINITY, f64::min);
    assert_eq!(best.best_val_loss, lowest);
}

#[test]
fn resume_continues_exactly_like_an_uninterrupted_run() {
    let straight = data_dir();
    assert_ok(&train(straight.path(), &["--epochs", "4"]));
    let resumed = data_dir();
    assert_ok(&train(resumed.path(), &["--epochs", "2"]));
    assert_ok(&train(resumed.path(), &["--epochs", "4", "--resume"]));
    let a = history(straight.path(), "last").history;
    let b = history(resumed.path(), "last").history;
    assert_eq!(a.len(), 4);
    assert_eq!(b.len(), 4);
    for (x, y) in a.iter().zip(&b) {
        for (p, q) in [
            (x.train_loss, y.train_loss),
            (x.val_loss, y.val_loss),
            (x.lr, y.lr),
        ] {
            assert!(((p - q) / p).abs() <= 1e-5, "epoch {}: {p} vs {q}", x.epoch);
        }
    }
}

#[test]
fn bf16_training_also_resumes_exactly() {
    let straight = data_dir();
    let bf16 = |data: &Path, args: &[&str]| train_in(data, "bf16", args);
    assert_ok(&bf16(straight.path(), &["--epochs", "3"]));
    let resumed = data_dir();
    assert_ok(&bf16(resumed.path(), &["--epochs", "2"]));
    assert_ok(&bf16(resumed.path(), &["--epochs", "3", "--resume"]));
    let a = history(straight.path(), "last");
    let b = history(resumed.path(), "last");
    assert_eq!(serde_json::to_value(a.config.precision).unwrap(), "bf16");
    for (x, y) in a.history.iter().zip(&b.history) {
        let rel = ((x.val_loss - y.val_loss) / x.val_loss).abs();
        assert!(
            rel <= 1e-5,
            "epoch {}: {} vs {}",
            x.epoch,
            x.val_loss,
            y.val_loss
        );
    }
    // Resuming in another precision is refused.
    let out = graspmap(&[
        "--data",
        resumed.path().to_str().unwrap(),
        "train",
        "--batch-size",
        "2",
        "--precision",
        "fp32",
        "--epochs",
        "4",
        "--resume",
    ]);
    assert_user_error(&out, &["--precision bf16"]);
}

#[test]
fn a_checkpoint_round_trips_bit_exactly() {
    tch::manual_seed(3);
    let dir = tempfile::tempdir().unwrap();
    let vs = nn::VarStore::new(tch::Device::Cpu);
    let _net = MiniUNet::new(&vs.root());
    let meta = CheckpointMeta {
        schema: CheckpointMeta::SCHEMA.to_owned(),
        config: TrainConfig::default(),
        epoch: 7,
        history: Vec::new(),
        best_val_loss: 0.5,
        best_epoch: 7,
        lr: 1e-4,
        plateau: Plateau::default(),
        adam_steps: 70,
        train_indices: vec![0, 2],
        val_indices: vec![1],
        trained_on: None,
    };
    save_checkpoint(&vs, &[], &meta, dir.path(), "best").unwrap();
    let (tensors, back) = read_checkpoint(dir.path(), "best").unwrap();
    assert_eq!(back, meta);
    let mut restored = nn::VarStore::new(tch::Device::Cpu);
    let _other = MiniUNet::new(&restored.root());
    graspmap::model::checkpoint::load_weights(&mut restored, &tensors, dir.path()).unwrap();
    let original = vs.variables();
    for (name, tensor) in restored.variables() {
        assert!(tensor.equal(&original[&name]), "{name} changed");
    }
}

#[test]
fn missing_or_bad_inputs_are_clear_errors() {
    let empty = tempfile::tempdir().unwrap();
    assert_user_error(&train(empty.path(), &["--epochs", "1"]), &["labels.json"]);

    let data = data_dir();
    assert_user_error(
        &train(data.path(), &["--epochs", "1", "--resume"]),
        &["last.safetensors"],
    );

    assert_ok(&train(data.path(), &["--epochs", "1"]));
    // The JSON beside a checkpoint is a copy for people: a torn one does not stop a resume,
    // since the training state travels inside the weights file.
    std::fs::write(data.path().join("affordance/last.json"), b"{ half").unwrap();
    assert_ok(&train(data.path(), &["--epochs", "2", "--resume"]));
    let last = data.path().join("affordance/last.safetensors");
    std::fs::write(&last, b"not a tensor file").unwrap();
    assert_user_error(
        &train(data.path(), &["--epochs", "3", "--resume"]),
        &["last.safetensors"],
    );

    let image = data.path().join("labels/YcbHammer_1_rgb.png");
    image::RgbImage::new(64, 64).save(&image).unwrap();
    assert_user_error(
        &train(data.path(), &["--epochs", "1"]),
        &["YcbHammer_1_rgb.png"],
    );

    assert_user_error(&train(data.path(), &["--epochs", "0"]), &["0"]);
    let out = graspmap(&["train", "--precision", "fp16"]);
    assert_user_error(&out, &["fp16"]);
    assert_user_error(&train(data.path(), &["--lr", "-1"]), &["-1"]);
}

#[test]
fn bench_reports_rust_timings_without_the_peer() {
    let out = graspmap(&[
        "--json",
        "-",
        "bench",
        "train",
        "--no-peer",
        "--steps",
        "2",
        "--rounds",
        "1",
    ]);
    assert_ok(&out);
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(report["schema"], "graspmap.bench/1");
    let rust = &report["results"]["rust"];
    assert!(rust["train_step_ms"].as_f64().unwrap() > 0.0);
    assert!(rust["infer_8_rotations_ms"].as_f64().unwrap() > 0.0);
    assert_eq!(rust["steps"], 2);
    assert!(report["results"]["python"].is_null());
}

#[test]
fn a_second_trainer_is_refused_while_the_first_holds_the_store() {
    let data = data_dir();
    let affordance = data.path().join("affordance");
    std::fs::create_dir_all(&affordance).unwrap();
    // This test's own process plays the first trainer.
    let lock = std::fs::File::create(affordance.join(".lock")).unwrap();
    lock.try_lock().unwrap();
    std::fs::write(
        affordance.join(".lock"),
        format!("{}\n", std::process::id()),
    )
    .unwrap();
    let out = train(data.path(), &["--epochs", "1"]);
    let holder = format!("process {}", std::process::id());
    assert_user_error(&out, &[".lock", &holder]);
    assert!(!affordance.join("last.safetensors").exists());
    drop(lock);
    assert_ok(&train(data.path(), &["--epochs", "1"]));
}

#[test]
fn sigterm_abandons_the_epoch_in_progress_and_resume_stays_exact() {
    let data = data_dir();
    let child = train_command(data.path(), "fp32", &["--epochs", "40"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let last = data.path().join("affordance/last.json");
    let start = std::time::Instant::now();
    while !last.exists() {
        assert!(start.elapsed().as_secs() < 60, "no epoch finished");
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    crate::common::send_signal(&child, libc::SIGTERM);
    let out = child.wait_with_output().unwrap();
    // What was kept is said on stderr, beside the error it ends with; stdout carries results.
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(143), "{stderr}");
    assert!(stderr.contains("interrupted by SIGTERM"), "{stderr}");
    assert!(stderr.contains("--resume"), "{stderr}");
    assert!(
        out.stdout.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stdout)
    );
    let kept = history(data.path(), "last").epoch;
    assert!((1..40).contains(&kept), "kept epoch {kept}");
    // Resumed for one epoch past the kept ones, whenever the signal landed: the same weights as
    // those epochs run straight through.
    let epochs = (kept + 1).to_string();
    assert_ok(&train(data.path(), &["--epochs", &epochs, "--resume"]));
    assert_eq!(history(data.path(), "last").epoch, kept + 1);
    let reference = data_dir();
    assert_ok(&train(reference.path(), &["--epochs", &epochs]));
    let weights = |d: &Path| std::fs::read(d.join("affordance/last.safetensors")).unwrap();
    assert_eq!(weights(data.path()), weights(reference.path()));
}

#[test]
#[cfg_attr(
    not(feature = "fault-injection"),
    ignore = "injects faults: needs --features fault-injection, which ./test.sh turns on"
)]
fn a_full_disk_at_any_write_of_an_epoch_fails_clearly_and_leaves_a_resumable_run() {
    let reference = data_dir();
    assert_ok(&train(reference.path(), &["--epochs", "1"]));
    let weights = |d: &Path| std::fs::read(d.join("affordance/last.safetensors")).unwrap();
    // An epoch writes best.safetensors, best.json, last.safetensors, last.json, losses.csv,
    // losses.png and training_vis/001.png, in that order: fail the checkpoint writes and one after.
    for n in [1, 2, 3, 4, 6] {
        let data = data_dir();
        let out = train_command(data.path(), "fp32", &["--epochs", "1"])
            .env("GRASPMAP_TEST_FAIL_WRITE", format!("{n}:eio"))
            .output()
            .unwrap();
        assert_user_error(&out, &["Input/output error", "affordance"]);
        let affordance = data.path().join("affordance");
        let resume = if affordance.join("last.safetensors").exists() {
            // What is there is whole: it reads back.
            read_checkpoint(&affordance, "last").unwrap();
            vec!["--epochs", "1", "--resume"]
        } else if affordance.join("best.safetensors").exists() {
            // A model without its resume state is still never replaced without asking.
            let refused = train(data.path(), &["--epochs", "1"]);
            assert_user_error(&refused, &["already holds a trained model", "--force"]);
            vec!["--epochs", "1", "--force"]
        } else {
            vec!["--epochs", "1"]
        };
        assert_ok(&train(data.path(), &resume));
        assert_eq!(weights(data.path()), weights(reference.path()), "write {n}");
    }
}
