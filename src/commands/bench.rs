//! `graspmap bench train`: training-step throughput and 8-rotation inference latency, side by side with the same network in Python PyTorch.

use std::path::PathBuf;
use std::process::Command;
use std::time::Instant;

use anyhow::{bail, Context as _};
use tch::{nn, Device, Kind, Tensor};

use super::Context;
use crate::cli::BenchTrainArgs;
use crate::output::write_report;
use crate::train::{loss, Adam};
use crate::unet::{MiniUNet, Precision};

/// Warm-up steps before timing, as the peer does.
const WARMUP: usize = 3;

#[derive(Debug, serde::Serialize)]
struct Side {
    train_step_ms: f64,
    train_images_per_s: f64,
    infer_8_rotations_ms: f64,
    steps: usize,
}

#[derive(Debug, serde::Serialize)]
struct BenchResults {
    precision: Precision,
    threads: u16,
    rust: Side,
    python: Option<Side>,
    /// Rust throughput over Python throughput (> 1: Rust is faster).
    train_ratio: Option<f64>,
    /// Python latency over Rust latency (> 1: Rust is faster).
    infer_ratio: Option<f64>,
}

fn median_ms(times: &mut [f64]) -> f64 {
    times.sort_by(f64::total_cmp);
    times[times.len() / 2] * 1e3
}

fn side(train: &mut [f64], infer: &mut [f64]) -> Side {
    let train_step_ms = median_ms(train);
    Side {
        train_step_ms,
        train_images_per_s: 8.0 / (train_step_ms / 1e3),
        infer_8_rotations_ms: median_ms(infer),
        steps: train.len(),
    }
}

fn timed(steps: usize, mut step: impl FnMut()) -> Vec<f64> {
    for _ in 0..WARMUP {
        step();
    }
    (0..steps)
        .map(|_| {
            let start = Instant::now();
            step();
            start.elapsed().as_secs_f64()
        })
        .collect()
}

/// Runs the command.
pub fn run(context: &Context, args: BenchTrainArgs) -> anyhow::Result<()> {
    let precision = args.precision.resolve();
    let precision_name = match precision {
        Precision::Fp32 => "fp32",
        Precision::Bf16 => "bf16",
    };
    tch::set_num_threads(context.threads as i32);
    tch::manual_seed(0);
    let vs = nn::VarStore::new(Device::Cpu);
    let net = MiniUNet::new(&vs.root());
    let mut adam = Adam::new(&vs, 1e-3);
    let x = Tensor::rand([8, 3, 128, 128], (Kind::Float, Device::Cpu));
    let target = Tensor::zeros([8, 1, 128, 128], (Kind::Float, Device::Cpu));
    let _ = target.narrow(2, 64, 1).narrow(3, 64, 1).fill_(1.0);

    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let python = root.join(".venv-bench/bin/python");
    if !args.no_peer {
        let status = Command::new(root.join("scripts/setup-bench-peer.sh"))
            .status()
            .context("running scripts/setup-bench-peer.sh")?;
        if !status.success() {
            bail!("scripts/setup-bench-peer.sh failed; rerun it, or pass --no-peer");
        }
    }
    let (mut rust_train, mut rust_infer) = (Vec::new(), Vec::new());
    let (mut py_train, mut py_infer) = (Vec::new(), Vec::new());
    // Alternate blocks so that both sides see the same machine state over time.
    for round in 0..args.rounds as usize {
        if !context.quiet {
            eprintln!("round {}/{}: rust", round + 1, args.rounds);
        }
        rust_train.extend(timed(args.steps as usize, || {
            let l = loss(&net, &x, &target, precision);
            l.backward();
            adam.step();
        }));
        rust_infer.extend(timed(args.steps as usize, || {
            tch::no_grad(|| {
                let _ = net.forward_with(&x, precision).sigmoid();
            })
        }));
        if args.no_peer {
            continue;
        }
        if !context.quiet {
            eprintln!("round {}/{}: python", round + 1, args.rounds);
        }
        let out = Command::new(&python)
            .arg(root.join("scripts/bench_peer.py"))
            .args(["--threads", &context.threads.to_string()])
            .args(["--precision", precision_name])
            .args(["--warmup", &WARMUP.to_string()])
            .args(["--steps", &args.steps.to_string()])
            .output()
            .with_context(|| format!("running {}", python.display()))?;
        if !out.status.success() {
            bail!(
                "the Python peer failed: {}",
                String::from_utf8_lossy(&out.stderr)
                    .lines()
                    .last()
                    .unwrap_or("")
            );
        }
        let report: serde_json::Value =
            serde_json::from_slice(&out.stdout).context("the Python peer printed no JSON")?;
        let list = |key: &str| -> anyhow::Result<Vec<f64>> {
            report[key]
                .as_array()
                .with_context(|| format!("the peer's JSON has no {key}"))?
                .iter()
                .map(|v| v.as_f64().context("a non-number timing"))
                .collect()
        };
        py_train.extend(list("train_step_s")?);
        py_infer.extend(list("infer_s")?);
    }
    let rust = side(&mut rust_train, &mut rust_infer);
    let python = (!py_train.is_empty()).then(|| side(&mut py_train, &mut py_infer));
    let results = BenchResults {
        precision,
        threads: context.threads,
        train_ratio: python
            .as_ref()
            .map(|p| rust.train_images_per_s / p.train_images_per_s),
        infer_ratio: python
            .as_ref()
            .map(|p| p.infer_8_rotations_ms / rust.infer_8_rotations_ms),
        rust,
        python,
    };
    context.say(&format!(
        "MiniUNet, batch 8, 128×128, {precision_name}, {} threads, median of {} steps",
        context.threads, results.rust.steps
    ));
    context.say(&format!(
        "{:<8} {:>14} {:>12} {:>22}",
        "", "train ms/step", "train img/s", "infer 8 rotations ms"
    ));
    for (name, s) in [
        ("rust", Some(&results.rust)),
        ("python", results.python.as_ref()),
    ] {
        if let Some(s) = s {
            context.say(&format!(
                "{name:<8} {:>14.1} {:>12.2} {:>22.1}",
                s.train_step_ms, s.train_images_per_s, s.infer_8_rotations_ms
            ));
        }
    }
    if let (Some(t), Some(i)) = (results.train_ratio, results.infer_ratio) {
        context.say(&format!(
            "rust/python: training throughput {t:.2}×, inference speed {i:.2}×"
        ));
    }
    if let Some(json) = &context.json {
        let resolved = serde_json::json!({
            "global": context,
            "steps": args.steps,
            "rounds": args.rounds,
            "warmup": WARMUP,
            "peer": !args.no_peer,
        });
        write_report(json, "bench", 0, &resolved, &results)?;
    }
    Ok(())
}
