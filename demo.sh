#!/usr/bin/env bash
# The main job on the bundled defaults, as far as it exists (eval comes next): collect the 60
# verified grasp labels into data/labels/ and train the affordance model for 30 epochs into
# data/affordance/ (both resume where an interrupted run stopped), then drop each training
# object into bin 1, save what the camera sees, and let the oracle pick it, with a video of the
# first attempt, into data/demo/.
set -euo pipefail
cd "$(dirname "$0")"
scripts/setup-libtorch.sh
cargo build --release --locked
bin=target/release/graspmap
out=data/demo
mkdir -p "$out"
"$bin" label --json "$out/label.json"
if [ -f data/affordance/last.json ]; then resume=(--resume); else resume=(); fi
"$bin" train --epochs 30 "${resume[@]}" --json "$out/train.json"
objects=$(python3 -c 'import json; print(",".join(json.load(open("assets/objects/split.json"))["train"]))' 2>/dev/null \
  || echo "YcbHammer,YcbMediumClamp,YcbMustardBottle,YcbPowerDrill,YcbTomatoSoupCan")
"$bin" scene --objects "$objects" --seed 0 --out "$out/scene.png" --depth "$out/depth.png" --json "$out/scene.json"
first=1
for object in ${objects//,/ }; do
  record=()
  if [ "$first" = 1 ]; then record=(--record "$out/$object.gif"); first=0; fi
  "$bin" grasp --object "$object" --seed 1 --oracle --image "$out/$object.png" \
    --json "$out/$object.json" "${record[@]}"
done
echo "results in $out/"
