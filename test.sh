#!/usr/bin/env bash
# Runs the whole test suite (unit, integration, physics, CLI) in release mode: the physics
# tests simulate full pick attempts, which a debug build runs far slower. libtorch (for tch) is
# installed into .venv/ first, and the system packages the tests call (ffmpeg for ffprobe, which
# checks the MP4 videos) with apt-get when they are missing and we are root; both are no-ops once
# they are there.
set -euo pipefail
cd "$(dirname "$0")"
scripts/setup-libtorch.sh
scripts/setup-system.sh ffmpeg
cargo test --release --locked "$@"
