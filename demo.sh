#!/usr/bin/env bash
# The main job on the bundled defaults: collect the 60 verified grasp labels into data/labels/,
# train the affordance model for 30 epochs into data/affordance/ (both resume where an
# interrupted run stopped), then evaluate it on the three tasks: the training objects, the
# unseen test objects, and emptying a bin of all 15 (with failure suppression). Each step also
# writes a JSON report into data/demo/; visualisations go to data/affordance/eval_*_vis/.
set -euo pipefail
cd "$(dirname "$0")"
scripts/setup-libtorch.sh
cargo build --release --locked
bin=target/release/graspmap
out=data/demo
mkdir -p "$out"
SECONDS=0
"$bin" label --json "$out/label.json"
# A rerun continues the model that data/affordance holds (same settings and labels).
"$bin" train --epochs 30 --json "$out/train.json"
"$bin" eval --task train --json "$out/eval_train.json"
"$bin" eval --task test --json "$out/eval_test.json"
"$bin" eval --task empty_bin --n-past-action 8 --record "$out/empty_bin.mp4" --json "$out/eval_empty_bin.json"
"$bin" report
echo "pipeline done in ${SECONDS} s; reports in $out/, the empty_bin video in $out/empty_bin.mp4, the page in data/report.html"
