#!/usr/bin/env bash
# Fingerprints of the main job's outputs, for proving that a refactor changed no behaviour:
# run it with the binary before and after the change, on the same machine, and diff the two
# files it writes. Usage: scripts/determinism.sh BINARY OUT.txt
# No output is kept in the repository: the hashes differ from one CPU to another.
#   - label on an empty data dir: sha256 of labels.json and of every label image;
#   - train --epochs 3: sha256 of best.safetensors;
#   - eval --task test --seed 0 and eval --task empty_bin --seeds 1-2 --n_past_action 8: every
#     attempt's drop seed, pixel, angle, outcome, reason and aimed-at object (timings left out).
set -euo pipefail
bin=$(realpath "$1")
out=$(realpath -m "$2")
data=$(mktemp -d)
trap 'rm -rf "$data"' EXIT
cd "$data"
{
  echo "# cpu: $(lscpu | sed -n 's/^Model name: *//p')"
  "$bin" --data "$data" --quiet label >/dev/null
  (cd "$data/labels" && sha256sum labels.json ./*_rgb.png)
  "$bin" --data "$data" --quiet train --epochs 3 >/dev/null
  (cd "$data/affordance" && sha256sum best.safetensors)
  # The tensors alone (the header after the 8-byte length, with any metadata, left out):
  # equal when only the file's metadata changed.
  python3 - "$data/affordance/best.safetensors" <<'PY'
import hashlib, json, struct, sys
raw = open(sys.argv[1], "rb").read()
(n,) = struct.unpack("<Q", raw[:8])
header = json.loads(raw[8:8 + n])
header.pop("__metadata__", None)
digest = hashlib.sha256(json.dumps(header, sort_keys=True).encode() + raw[8 + n:]).hexdigest()
print(f"{digest}  best.safetensors tensors")
PY
  "$bin" --data "$data" --quiet eval --task test --seed 0 --json test.json >/dev/null
  "$bin" --data "$data" --quiet eval --task empty_bin --seeds 1-2 --n_past_action 8 \
    --json empty_bin.json >/dev/null
  for report in test.json empty_bin.json; do
    python3 - "$report" <<'PY'
import json, sys
report = json.load(open(sys.argv[1]))
for run in report["results"]["runs"]:
    for a in run["attempts"]:
        g = a["grasp"] or {}
        print(sys.argv[1], a["drop_seed"], a["attempt"], a["object"], g.get("u"), g.get("v"),
              g.get("angle_deg"), a["success"], a["reason"], a["aimed_at"], a["held"], a["moved"])
PY
  done
} >"$out"
echo "wrote $out ($(wc -l <"$out") lines)" >&2
