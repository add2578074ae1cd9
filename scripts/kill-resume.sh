#!/usr/bin/env bash
# SIGKILL at random moments: label and train are each killed K times (default 10) at a random
# moment, then rerun (train with --resume) to the end; each end state must be identical to an
# uninterrupted run's (labels: every file's bytes; train: last.safetensors and best.safetensors).
# Usage: scripts/kill-resume.sh [K] [SEED]
#   JSON=FILE  also write the kills to FILE, a failed run's included: {"k", "seed", "ok", "kills":
#              [{"what": "label"|"train", "delay_s", "resume"}]}, each kill listed once it resumed
set -euo pipefail
cd "$(dirname "$0")/.."
k=${1:-10}
seed=${2:-$RANDOM}
bin=$(realpath target/release/graspmap)
[ -x "$bin" ] || cargo build --release --locked
work=$(mktemp -d)
kills=()
# The summary is written on every exit, so that a failed run's JSON says how far it came.
finish() {
  local status=$?
  rm -rf "$work"
  if [[ -n ${JSON:-} ]]; then
    local ok=false
    [[ $status != 0 ]] || ok=true
    (IFS=,; echo "{\"k\": $k, \"seed\": $seed, \"ok\": $ok, \"kills\": [${kills[*]}]}") >"$JSON"
  fi
}
trap finish EXIT
delays() { python3 -c "import random; r = random.Random($seed + $2); print(' '.join(f'{r.uniform(0.05, $1):.2f}' for _ in range($k)))"; }
fingerprint() { (cd "$1" && find . -type f ! -name .lock ! -name '*.json.tmp*' | sort | xargs sha256sum); }

"$bin" --quiet --data "$work/ref" label >/dev/null
fingerprint "$work/ref/labels" >"$work/labels.ref"
start=$SECONDS
"$bin" --quiet --data "$work/ref" train --epochs 3 >/dev/null
train_seconds=$((SECONDS - start))
(cd "$work/ref/affordance" && sha256sum last.safetensors best.safetensors) >"$work/train.ref"

i=0
for delay in $(delays 9 1); do
  i=$((i + 1))
  d="$work/label-$i"
  "$bin" --quiet --data "$d" label >/dev/null 2>&1 &
  pid=$!
  sleep "$delay"
  kill -9 "$pid" 2>/dev/null || true
  wait "$pid" 2>/dev/null || true
  "$bin" --quiet --data "$d" label >/dev/null
  fingerprint "$d/labels" | diff -q - "$work/labels.ref" >/dev/null \
    || { echo "kill-resume: label killed at ${delay} s resumed to a different dataset" >&2; exit 1; }
  echo "label: killed at ${delay} s, resumed to the identical dataset"
  kills+=("{\"what\": \"label\", \"delay_s\": $delay, \"resume\": false}")
done
i=0
for delay in $(delays "$train_seconds" 2); do
  i=$((i + 1))
  d="$work/train-$i"
  mkdir -p "$d" && cp -r "$work/ref/labels" "$d/labels"
  "$bin" --quiet --data "$d" train --epochs 3 >/dev/null 2>&1 &
  pid=$!
  sleep "$delay"
  kill -9 "$pid" 2>/dev/null || true
  wait "$pid" 2>/dev/null || true
  if [ -f "$d/affordance/last.safetensors" ]; then resume=(--resume); else resume=(); fi
  "$bin" --quiet --data "$d" train --epochs 3 "${resume[@]}" >/dev/null
  (cd "$d/affordance" && sha256sum last.safetensors best.safetensors) | diff -q - "$work/train.ref" >/dev/null \
    || { echo "kill-resume: train killed at ${delay} s resumed to different weights" >&2; exit 1; }
  echo "train: killed at ${delay} s (${resume[*]:-from scratch}), resumed to identical weights"
  kills+=("{\"what\": \"train\", \"delay_s\": $delay, \"resume\": $([[ ${#resume[@]} -gt 0 ]] && echo true || echo false)}")
done
echo "kill-resume: $k label and $k train kills (seed $seed), every one resumed to the identical end state"
