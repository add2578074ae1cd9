#!/usr/bin/env bash
# The issue-14 measurement, end to end from nothing: for each variant (input × clutter), label 60
# labels into its own data dir, train 30 epochs, run every eval on the same seeded scenes, then
# print the markdown table (BENCHMARKS.md#input-and-label-variants) and write a JSON
# summary with the decision rule of docs/departures.md evaluated. Deterministic from the seeds
# (the times aside).
#
# Usage: scripts/variants.sh [OUT_DIR]           (default target/variants; reruns reuse nothing)
#   GRASPMAP=path/to/graspmap  use that binary instead of building target/release/graspmap
#   VARIANTS="rgb:1 rgbd:1 rgb:3 rgbd:3"  input:clutter[:per-object] of each variant; the first
#                                          is the baseline the others are compared with
#   EXTRA=2   how many of the best variants (baseline included) also get the flag combinations
#             (--verify-top 0, no --n-past-action, both), after every variant's core evals
#   EPOCHS=30 TEST_SEEDS=0,1000,2000 EMPTY_SEEDS=1-10   only to try the script out quickly
set -euo pipefail
cd "$(dirname "$0")/.."
out=$(realpath -m "${1:-target/variants}")
variants=${VARIANTS:-"rgb:1 rgbd:1 rgb:3 rgbd:3"}
extra=${EXTRA:-2}
epochs=${EPOCHS:-30}
test_seeds=${TEST_SEEDS:-0,1000,2000}
empty_seeds=${EMPTY_SEEDS:-1-10}
if [[ -z "${GRASPMAP:-}" ]]; then
  scripts/setup-libtorch.sh >/dev/null
  cargo build --release --locked --quiet
  bin=$(realpath target/release/graspmap)
else
  bin=$(realpath "$GRASPMAP")
fi
rm -rf "$out"
mkdir -p "$out"
echo "variants: $variants -> $out (binary $bin, commit $(git rev-parse --short HEAD))" >&2

name_of() { # input:clutter[:per] -> rgb-c1[-p24]
  IFS=: read -r input clutter per <<<"$1"
  echo "$input-c$clutter${per:+-p$per}"
}

# eval DIR NAME ARGS...: one eval into DIR/eval/NAME.json, named for what it runs as
# scripts/benchmarks.sh names its own (empty_bin-np8+verify-top-0).
run_eval() {
  local dir=$1 name=$2
  shift 2
  "$bin" --data "$dir" --quiet eval "$@" --json "$dir/eval/$name.json" >/dev/null
}

core_evals() {
  local dir=$1
  run_eval "$dir" train-seed0 --task train --seeds 0
  run_eval "$dir" test --task test --seeds "$test_seeds"
  run_eval "$dir" empty_bin-np8 --task empty_bin --seeds "$empty_seeds" --n-past-action 8
}

# Most telling first: is the depth test still needed, then does suppression matter.
extra_evals() {
  local dir=$1
  run_eval "$dir" train-seed0+verify-top-0 --task train --seeds 0 --verify-top 0
  run_eval "$dir" test+verify-top-0 --task test --seeds "$test_seeds" --verify-top 0
  run_eval "$dir" empty_bin-np8+verify-top-0 --task empty_bin --seeds "$empty_seeds" --n-past-action 8 --verify-top 0
  run_eval "$dir" empty_bin --task empty_bin --seeds "$empty_seeds"
  run_eval "$dir" empty_bin+verify-top-0 --task empty_bin --seeds "$empty_seeds" --verify-top 0
}

for v in $variants; do
  IFS=: read -r input clutter per <<<"$v"
  dir="$out/$(name_of "$v")"
  mkdir -p "$dir/eval"
  echo "== $(name_of "$v"): label, train, evals ($(date -u +%H:%M:%S))" >&2
  "$bin" --data "$dir" --quiet label --clutter "$clutter" --per-object "${per:-12}" \
    --json "$dir/label.json" >/dev/null
  "$bin" --data "$dir" --quiet train --epochs "$epochs" --input "$input" --json "$dir/train.json" >/dev/null
  core_evals "$dir"
done

# The best variants by the core evals (mean of the test rate and the empty_bin fraction moved),
# the baseline among them.
best=$(python3 - "$out" $variants <<'PY'
import json, sys
out, variants = sys.argv[1], sys.argv[2:]
def name(v):
    parts = v.split(":")
    return f"{parts[0]}-c{parts[1]}" + (f"-p{parts[2]}" if len(parts) > 2 else "")
def score(n):
    t = json.load(open(f"{out}/{n}/eval/test.json"))["results"]["success"]["rate"]
    e = json.load(open(f"{out}/{n}/eval/empty_bin-np8.json"))["results"]["moved"]["mean"] / 15
    return (t + e) / 2
names = [name(v) for v in variants]
print(" ".join(sorted(names, key=lambda n: -score(n))))
PY
)
for name in $(echo "$best" | tr ' ' '\n' | head -n "$extra"); do
  echo "== $name: extra flag combinations ($(date -u +%H:%M:%S))" >&2
  extra_evals "$out/$name"
done

python3 scripts/variants_table.py "$out" $variants
