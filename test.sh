#!/usr/bin/env bash
# Runs the whole test suite (unit, integration, physics, CLI) in release mode: the physics
# tests simulate full pick attempts, which a debug build runs far slower. libtorch (for tch) is
# installed into .venv/ first; a no-op once it is there.
set -euo pipefail
cd "$(dirname "$0")"
scripts/setup-libtorch.sh
cargo test --release --locked "$@"
