//! `graspmap bench`: training-step throughput and 8-rotation inference latency side by side with
//! the same network in Python PyTorch (`train`), and `--precision auto`'s measurement (`precision`).

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

use anyhow::{bail, Context as _};
use tch::{nn, Device, Kind, Tensor};

use super::Context;
use crate::model::autotune;
use crate::model::inference::network_layout;
use crate::model::train::{loss, Adam};
use crate::model::unet::{MiniUNet, Precision};
use crate::named::Named;
use crate::present::envelope::write_report;

/// The Python peer, compiled in so that an installed binary can run it from anywhere.
const PEER_SCRIPT: &str = include_str!("../../scripts/bench_peer.py");
/// Where the peer's Python lives when `--python` is not given, relative to the current
/// directory: what scripts/setup-bench-peer.sh installs in a checkout.
const PEER_PYTHON: &str = ".venv-bench/bin/python";
/// The installer of [`PEER_PYTHON`], relative to a checkout.
const PEER_SETUP: &str = "scripts/setup-bench-peer.sh";

/// What `graspmap bench train` measures.
#[derive(Debug, Clone)]
pub(crate) struct BenchConfig {
    /// Timed steps per block and side (after the warm-up).
    pub(crate) steps: u32,
    /// Blocks per side, alternating Rust and Python.
    pub(crate) rounds: u32,
    /// Precision of both sides.
    pub(crate) precision: Precision,
    /// The peer's Python; `None` times the Rust side only.
    pub(crate) peer: Option<PeerPython>,
}

/// Which Python runs the peer.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum PeerPython {
    /// `.venv-bench/bin/python` under the current directory, installed on first use.
    Checkout,
    /// A Python with torch 2.13 that the user named.
    Given(PathBuf),
}

impl PeerPython {
    /// The interpreter to run, installing the checkout's environment when it is missing.
    fn resolve(&self) -> anyhow::Result<PathBuf> {
        match self {
            PeerPython::Given(path) => Ok(path.clone()),
            PeerPython::Checkout => {
                if Path::new(PEER_SETUP).is_file() {
                    let status = Command::new(PEER_SETUP)
                        .status()
                        .with_context(|| format!("running {PEER_SETUP}"))?;
                    if !status.success() {
                        bail!("{PEER_SETUP} failed; rerun it, or pass --no-peer");
                    }
                } else if !Path::new(PEER_PYTHON).is_file() {
                    bail!(
                        "no Python peer: {PEER_PYTHON} is missing here and {PEER_SETUP} is not \
                         in this directory; run bench from a graspmap checkout, pass --python \
                         PATH (a python with torch 2.13), or pass --no-peer"
                    );
                }
                Ok(PathBuf::from(PEER_PYTHON))
            }
        }
    }
}

/// Warm-up steps before timing, as the peer does.
const WARMUP: usize = 3;

#[derive(Debug, serde::Serialize)]
struct Side {
    train_step_ms: f64,
    train_images_per_s: f64,
    infer_8_rotations_ms: f64,
    steps: usize,
}

/// The machine's convolution peak against what the network achieves, both in `precision`.
#[derive(Debug, serde::Serialize)]
struct Throughput {
    /// The peak: a 256 → 256 3 × 3 convolution over a batch of 8 at 64 × 64 (38.7 GFLOP), the
    /// shape oneDNN runs best, median of the timed steps.
    conv_peak_gflops: f64,
    /// Work of the 8-rotation inference (8 forward passes over 128 × 128).
    infer_gflop: f64,
    /// What the Rust side's 8-rotation inference achieves.
    infer_gflops: f64,
    /// `infer_gflops` over `conv_peak_gflops`.
    infer_share_of_peak: f64,
    /// What the Rust side's training step achieves, its work counted as three forward passes
    /// (the backward pass computes two products per forward one).
    train_gflops: f64,
    /// `train_gflops` over `conv_peak_gflops`.
    train_share_of_peak: f64,
}

#[derive(Debug, serde::Serialize)]
struct BenchResults {
    precision: Precision,
    threads: u16,
    throughput: Throughput,
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

/// Times the peak convolution of [`Throughput::conv_peak_gflops`] in `precision`.
fn conv_peak_gflops(steps: usize, precision: Precision) -> f64 {
    let kind = match precision {
        Precision::Fp32 => Kind::Float,
        Precision::Bf16 => Kind::BFloat16,
    };
    let flop = 2.0 * (256.0 * 256.0 * 9.0) * (8.0 * 64.0 * 64.0);
    // The better of the two layouts: oneDNN's fastest kernel for this shape is the peak.
    [false, true]
        .into_iter()
        .map(|channels_last| {
            let layout = |t: Tensor| match channels_last {
                false => t,
                true => crate::model::unet::channels_last(&t),
            };
            let x = layout(Tensor::rand([8, 256, 64, 64], (kind, Device::Cpu)));
            let w = layout(Tensor::rand([256, 256, 3, 3], (kind, Device::Cpu)));
            let mut times = timed(steps, || {
                tch::no_grad(|| {
                    let _ = x.conv2d(&w, None::<Tensor>, [1, 1], [1, 1], [1, 1], 1);
                })
            });
            flop / (median_ms(&mut times) / 1e3) / 1e9
        })
        .fold(0.0, f64::max)
}

/// Runs the command.
pub(crate) fn run(context: &Context, args: BenchConfig) -> anyhow::Result<()> {
    let precision = args.precision;
    crate::model::use_threads(context.threads);
    tch::manual_seed(0);
    let vs = nn::VarStore::new(Device::Cpu);
    let net = MiniUNet::new(&vs.root());
    let mut adam = Adam::new(&vs, 1e-3);
    let x = Tensor::rand([8, 3, 128, 128], (Kind::Float, Device::Cpu));
    let target = Tensor::zeros([8, 1, 128, 128], (Kind::Float, Device::Cpu));
    let _ = target.narrow(2, 64, 1).narrow(3, 64, 1).fill_(1.0);
    let python = args.peer.as_ref().map(PeerPython::resolve).transpose()?;

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
        // In the layout `eval` runs the network in.
        let batch = network_layout(&x, precision);
        rust_infer.extend(timed(args.steps as usize, || {
            tch::no_grad(|| {
                let _ = net.forward_with(&batch, precision).sigmoid();
            })
        }));
        let Some(python) = &python else { continue };
        if !context.quiet {
            eprintln!("round {}/{}: python", round + 1, args.rounds);
        }
        let (train, infer) = run_peer(python, context.threads, &args)?;
        py_train.extend(train);
        py_infer.extend(infer);
    }
    let rust = side(&mut rust_train, &mut rust_infer);
    let python = (!py_train.is_empty()).then(|| side(&mut py_train, &mut py_infer));
    let conv_peak_gflops = conv_peak_gflops(args.steps as usize, precision);
    let infer_gflop = 8.0 * crate::model::unet::forward_flops(3, 128, 128) / 1e9;
    let infer_gflops = infer_gflop / (rust.infer_8_rotations_ms / 1e3);
    let train_gflops = 3.0 * infer_gflop / (rust.train_step_ms / 1e3);
    let results = BenchResults {
        precision,
        threads: context.threads,
        throughput: Throughput {
            conv_peak_gflops,
            infer_gflop,
            infer_gflops,
            infer_share_of_peak: infer_gflops / conv_peak_gflops,
            train_gflops,
            train_share_of_peak: train_gflops / conv_peak_gflops,
        },
        train_ratio: python
            .as_ref()
            .map(|p| rust.train_images_per_s / p.train_images_per_s),
        infer_ratio: python
            .as_ref()
            .map(|p| p.infer_8_rotations_ms / rust.infer_8_rotations_ms),
        rust,
        python,
    };
    print_results(context, &results);
    if let Some(json) = &context.json {
        let resolved = serde_json::json!({
            "global": context,
            "steps": args.steps,
            "rounds": args.rounds,
            "warmup": WARMUP,
            "peer": args.peer.is_some(),
        });
        write_report(json, "bench", 0, &resolved, &results)?;
    }
    Ok(())
}

/// `graspmap bench precision`: times fp32 and bf16 afresh under this process's ISA cap, keeps
/// the result as `--precision auto`'s choice for this machine, and shows both.
pub(crate) fn precision(context: &Context) -> anyhow::Result<()> {
    crate::model::use_threads(context.threads);
    let (measured, kept) = autotune::remeasure()?;
    let key = &measured.machine;
    context.say(&format!(
        "{}, {}, {} threads",
        key.cpu_model,
        key.caps(),
        measured.threads
    ));
    context.say(&format!(
        "{:<19} {:>14} {:>22}",
        "", "train ms/step", "infer 8 rotations ms"
    ));
    for (name, t) in [("fp32", &measured.fp32), ("bf16", &measured.bf16)] {
        context.say(&format!(
            "{name:<19} {:>14.1} {:>22.1}",
            t.train_step_ms, t.infer_ms
        ));
    }
    context.say(&format!(
        "{:<19} {:>14.1} {:>22}",
        "fp32, channels_last", measured.fp32_train_channels_last_ms, "–"
    ));
    context.say(&format!(
        "auto: {} for training{}, {} for inference; {}",
        measured.train.name(),
        match measured.fp32_train_channels_last {
            true => " (fp32 in channels_last)",
            false => "",
        },
        measured.infer.name(),
        match &kept {
            Some(path) => format!("kept in {}", path.display()),
            None => "not kept (no HOME or XDG_CACHE_HOME)".to_owned(),
        }
    ));
    if let Some(json) = &context.json {
        let resolved = serde_json::json!({ "global": context, "cache": kept });
        write_report(json, "bench", 0, &resolved, &measured)?;
    }
    Ok(())
}

/// One block of the Python peer: its training-step and inference timings in seconds.
fn run_peer(
    python: &Path,
    threads: u16,
    args: &BenchConfig,
) -> anyhow::Result<(Vec<f64>, Vec<f64>)> {
    let precision_name = args.precision.name();
    let mut child = Command::new(python)
        .arg("-")
        .args(["--threads", &threads.to_string()])
        .args(["--precision", precision_name])
        .args(["--warmup", &WARMUP.to_string()])
        .args(["--steps", &args.steps.to_string()])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .with_context(|| format!("running {}", python.display()))?;
    if let Some(mut stdin) = child.stdin.take() {
        stdin
            .write_all(PEER_SCRIPT.as_bytes())
            .with_context(|| format!("sending the peer script to {}", python.display()))?;
    }
    let out = child
        .wait_with_output()
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
    Ok((list("train_step_s")?, list("infer_s")?))
}

fn print_results(context: &Context, results: &BenchResults) {
    context.say(&format!(
        "MiniUNet, batch 8, 128×128, {}, {} threads, median of {} steps",
        results.precision.name(),
        results.threads,
        results.rust.steps
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
    let t = &results.throughput;
    context.say(&format!(
        "8-rotation inference: {:.1} GFLOP at {:.0} GFLOP/s = {:.0} % of the machine's conv peak, {:.0} GFLOP/s (256→256 3×3 at 64×64, batch 8)",
        t.infer_gflop,
        t.infer_gflops,
        100.0 * t.infer_share_of_peak,
        t.conv_peak_gflops
    ));
    context.say(&format!(
        "training step: {:.0} GFLOP/s = {:.0} % of that peak (3 forward passes' work)",
        t.train_gflops,
        100.0 * t.train_share_of_peak
    ));
    if let (Some(t), Some(i)) = (results.train_ratio, results.infer_ratio) {
        context.say(&format!(
            "rust/python: training throughput {t:.2}×, inference speed {i:.2}×"
        ));
    }
}
