#!/usr/bin/env bash
# Runs the whole test suite (unit, integration, physics, CLI) in release mode: the physics
# tests simulate full pick attempts, which a debug build runs far slower.
set -euo pipefail
cd "$(dirname "$0")"
cargo test --release --locked "$@"
