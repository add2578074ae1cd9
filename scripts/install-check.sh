#!/usr/bin/env bash
# Shows that an installed graspmap runs from anywhere: `cargo install` into a fresh root
# (reusing target/, so nothing is built twice), then, from an empty directory, the main job in
# small: label, train --epochs 1 and eval --task train. The models are embedded in the binary;
# libtorch is found through the rpath into this checkout's .venv/.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(mktemp -d)
work=$(mktemp -d)
trap 'rm -rf "$root" "$work"' EXIT
cargo install --path . --locked --root "$root" --target-dir target --quiet
bin="$root/bin/graspmap"
cd "$work"
"$bin" --quiet label --json label.json >/dev/null
"$bin" --quiet train --epochs 1 --json train.json >/dev/null
"$bin" --quiet eval --task train --json eval.json >/dev/null
for report in label/1 train/1 eval/2; do
  name=${report%/*}
  grep -q "\"schema\": \"graspmap.$report\"" "$name.json" || {
    echo "install-check: $name.json is not a graspmap.$report report" >&2
    exit 1
  }
done
test -f data/affordance/best.safetensors
echo "install-check: the installed binary labelled, trained and evaluated in an empty directory"
