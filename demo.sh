#!/usr/bin/env bash
# The main job on the bundled defaults: collect the 60 verified grasp labels into data/labels/,
# train the affordance model for 30 epochs into data/affordance/ (both resume where an
# interrupted run stopped), then evaluate it on the three tasks: the training objects (seed 0),
# the unseen test objects (seeds 0, 1000, 2000, as the README's table), and emptying a bin of
# all 15 (seed 2, with failure suppression); then the random and oracle baselines on the same
# tasks and seeds, which the report's first table shows beside the model. Each step also
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
"$bin" eval --task test --seeds 0,1000,2000 --json "$out/eval_test.json"
"$bin" eval --task empty_bin --n-past-action 8 --record "$out/empty_bin.mp4" --json "$out/eval_empty_bin.json"
# The baselines: random ignores failure memory, the oracle uses it as the model does.
for policy in random oracle; do
  memory=()
  if [ "$policy" = oracle ]; then memory=(--n-past-action 8); fi
  "$bin" --quiet eval --task train --policy "$policy" --json "$out/eval_train_$policy.json" >/dev/null
  "$bin" --quiet eval --task test --seeds 0,1000,2000 --policy "$policy" --json "$out/eval_test_$policy.json" >/dev/null
  "$bin" --quiet eval --task empty_bin --policy "$policy" "${memory[@]}" --json "$out/eval_empty_bin_$policy.json" >/dev/null
done
"$bin" report
echo "pipeline done in ${SECONDS} s; reports in $out/, the empty_bin video in $out/empty_bin.mp4, the page in data/report.html"
