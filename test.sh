#!/usr/bin/env bash
# Runs the whole test suite (unit, integration, physics, CLI) in release mode: the physics
# tests simulate full pick attempts, which a debug build runs far slower. libtorch (for tch) is
# installed into .venv/ first, and the system packages the tests call with apt-get when they are
# missing and we are root: ffmpeg (ffprobe checks the MP4 videos), chromium and chromium-driver
# (the browser test drives the labelling page through WebDriver), slurm-wlm and munge. All are no-ops once they are
# there; without root the tests that need a package fail with the command that installs it.
# slurm-wlm and munge give tests/suite/slurm.rs a real one-node Slurm (scripts/slurm/). The
# benchmark tables' renderer (scripts/benchmarks/) has its own unit tests, in Python, run first:
# they take seconds and need no build.
set -euo pipefail
cd "$(dirname "$0")"
python3 -m unittest discover -s scripts/benchmarks -q
scripts/setup-libtorch.sh
scripts/setup-system.sh ffmpeg chromium chromium-driver slurm-wlm munge
# fault-injection compiles in the crash tests' switches (Cargo.toml); only graspmap itself is
# built apart from `cargo build`'s, the dependencies are shared.
cargo test --release --locked --features fault-injection "$@"
