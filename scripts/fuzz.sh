#!/usr/bin/env bash
# The long fuzz pass: every parser and loader fed random mutations of real files (the `mod fuzz` beside each parser).
# CI runs 1,000 cases per parser as part of ./test.sh; this runs 100,000 per JSON file (labels,
# clicks, split, progress, the checkpoint's training state) and 10,000 per binary or XML format
# (safetensors, URDF, OBJ, STL, PNG, JPEG), and prints the counts. Usage: scripts/fuzz.sh [SCALE]
# (SCALE multiplies both counts; 0.01 for a quick look).
#   JSON=FILE  also write every pass to FILE: {"scale", "passes": [{"filter", "cases", "seconds", "ok"}]}
# A failed pass does not stop the others; the exit status is 1 if any failed.
set -euo pipefail
cd "$(dirname "$0")/.."
scale=${1:-1}
json=$(python3 -c "print(max(1, int(100000 * $scale)))")
binary=$(python3 -c "print(max(1, int(10000 * $scale)))")
scripts/setup-libtorch.sh
passes=()
status=0
run() {
  local cases=$1 filter=$2 ok=true
  local start=$SECONDS
  if GRASPMAP_FUZZ_CASES=$cases cargo test --release --locked --lib -- --quiet "fuzz::$filter" >/dev/null; then
    echo "$filter: $cases cases each, no panic, no case over 5 s, under 2 GiB ($((SECONDS - start)) s)"
  else
    echo "$filter: FAILED after $((SECONDS - start)) s ($cases cases each)" >&2
    ok=false
    status=1
  fi
  passes+=("{\"filter\": \"$filter\", \"cases\": $cases, \"seconds\": $((SECONDS - start)), \"ok\": $ok}")
}
run "$json" fuzz_json_
run "$binary" fuzz_safetensors
run "$binary" fuzz_urdf
run "$binary" fuzz_obj
run "$binary" fuzz_stl
run "$binary" fuzz_png
run "$binary" fuzz_jpeg
if [[ -n ${JSON:-} ]]; then
  (IFS=,; echo "{\"scale\": \"$scale\", \"passes\": [${passes[*]}]}") >"$JSON"
fi
exit $status
