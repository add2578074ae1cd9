#!/usr/bin/env bash
# The long fuzz pass: every parser and loader fed random mutations of real files (the `mod fuzz` beside each parser).
# CI runs 1,000 cases per parser as part of ./test.sh; this runs 100,000 per JSON file (labels,
# clicks, split, progress, the checkpoint's training state) and 10,000 per binary or XML format
# (safetensors, URDF, OBJ, STL, PNG, JPEG), and prints the counts. Usage: scripts/fuzz.sh [SCALE]
# (SCALE multiplies both counts; 0.01 for a quick look).
set -euo pipefail
cd "$(dirname "$0")/.."
scale=${1:-1}
json=$(python3 -c "print(max(1, int(100000 * $scale)))")
binary=$(python3 -c "print(max(1, int(10000 * $scale)))")
scripts/setup-libtorch.sh
run() {
  local cases=$1 filter=$2
  local start=$SECONDS
  GRASPMAP_FUZZ_CASES=$cases cargo test --release --locked --lib -- --quiet "fuzz::$filter" \
    >/dev/null
  echo "$filter: $cases cases each, no panic, no case over 5 s, under 2 GiB ($((SECONDS - start)) s)"
}
run "$json" fuzz_json_
run "$binary" fuzz_safetensors
run "$binary" fuzz_urdf
run "$binary" fuzz_obj
run "$binary" fuzz_stl
run "$binary" fuzz_png
run "$binary" fuzz_jpeg
