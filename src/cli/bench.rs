//! The flags of `graspmap bench`.

use std::path::PathBuf;

use clap::{Args, Subcommand};

use super::values::PrecisionChoice;

/// What `graspmap bench` measures.
#[derive(Debug, Subcommand)]
pub(crate) enum BenchCommand {
    /// Training-step throughput and 8-rotation inference latency, Rust and Python alternating.
    Train(BenchTrainArgs),
    /// `--precision auto`'s measurement, taken afresh: fp32 and bf16 on a training step and an
    /// 8-rotation inference under this process's ISA cap, the choice, and where it is kept.
    Precision,
}

/// `graspmap bench train`.
#[derive(Debug, Args)]
pub(crate) struct BenchTrainArgs {
    /// Timed steps per block and side (after 3 warm-up steps).
    #[arg(long, default_value_t = 20, value_parser = clap::value_parser!(u32).range(1..))]
    pub(crate) steps: u32,
    /// Blocks per side, alternating Rust and Python.
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u32).range(1..))]
    pub(crate) rounds: u32,
    /// Precision of both sides.
    #[arg(long, value_enum, default_value_t = PrecisionChoice::Auto)]
    pub(crate) precision: PrecisionChoice,
    /// Time only the Rust side (no Python environment needed).
    #[arg(long, conflicts_with = "python")]
    pub(crate) no_peer: bool,
    /// The peer's Python, with torch 2.13 [default: ./.venv-bench/bin/python, installed by
    /// scripts/setup-bench-peer.sh when run from a checkout].
    #[arg(long, value_name = "PATH")]
    pub(crate) python: Option<PathBuf>,
}
