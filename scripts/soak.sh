#!/usr/bin/env bash
# Physics soak: N empty_bin scenes with random seeds, with the random policy and (when a trained
# model exists, or --model-scenes M) the model, checking after every physics step that every
# body's pose and velocity are finite and no object is sunk more than 5 mm into the ground or a
# tote, and that every attempt ends with a reason and the process with no panic.
# Usage: scripts/soak.sh N [M] [SEED]   (M model scenes, default N/10; SEED picks the scenes)
#   GRASPMAP=path/to/graspmap  use that binary instead of building target/release/graspmap
#   DATA=DIR  the data dir whose model the model scenes use (default data, as ./demo.sh leaves it)
#   OBJECTS_DIR=DIR  the scenes' objects from DIR (--objects-dir, e.g. the public YCB meshes) and
#     its split.json, instead of the 15 bundled ones
#   JSON=FILE  also write the counts per policy to FILE: {"seed", "ok", "policies": {"random"|"model":
#     {"scenes", "attempts", "panics", "no_reason", "nonfinite", "sunk"}}} (0 scenes: not run)
# Prints each violation with the seed and attempt that reproduce it, and exits 1 if any.
set -euo pipefail
cd "$(dirname "$0")/.."
n=${1:?usage: scripts/soak.sh N [MODEL_SCENES] [SEED]}
m=${2:-$((n / 10))}
seed=${3:-$RANDOM}
bin=${GRASPMAP:-target/release/graspmap}
data=${DATA:-data}
objects=()
if [ -n "${OBJECTS_DIR:-}" ]; then objects=(--objects-dir "$OBJECTS_DIR"); fi
[ -x "$bin" ] || cargo build --release --locked
out=$(mktemp -d)
# Distinct seeds from one generator, so a run is repeatable from its SEED.
seeds() { python3 -c "import random; r = random.Random($seed); print(','.join(str(s) for s in r.sample(range(1, 10**9), $1)))"; }
echo "soak: $n random-policy scenes and $m model scenes, seed $seed, objects ${OBJECTS_DIR:-bundled}, reports in $out" >&2
status=0
sweep() {
  local policy=$1 count=$2 list
  [ "$count" -gt 0 ] || return 0
  list=$(seeds "$count")
  # Two processes, one per core: the simulator is single-threaded.
  local half=$(( (count + 1) / 2 )) part=0 pids=()
  IFS=, read -r -a all <<<"$list"
  for chunk in "${all[*]:0:$half}" "${all[*]:$half}"; do
    [ -n "$chunk" ] || continue
    part=$((part + 1))
    "$bin" --data "$data" ${objects[@]+"${objects[@]}"} --quiet --threads 1 --json "$out/$policy-$part.json" eval --task empty_bin \
      --policy "$policy" --seeds "${chunk// /,}" --check-invariants \
      >"$out/$policy-$part.log" 2>"$out/$policy-$part.err" &
    pids+=($!)
  done
  local failed=0 pid
  for pid in "${pids[@]}"; do
    wait "$pid" || { echo "soak: a $policy sweep exited with status $?" >&2; failed=1; }
  done
  for part_log in "$out/$policy"-*.err; do
    if grep -q "panicked" "$part_log"; then
      echo "soak: a panic in $part_log" >&2
      failed=1
    fi
    grep "invariant broken" "$part_log" >&2 || true
  done
  python3 - "$out" "$policy" <<'PY' || failed=1
import glob, json, sys
out, policy = sys.argv[1], sys.argv[2]
c = dict(scenes=0, attempts=0, panics=0, no_reason=0, nonfinite=0, sunk=0)
broken = 0
for path in sorted(glob.glob(f"{out}/{policy}-*.json")):
    report = json.load(open(path))
    for run in report["results"]["runs"]:
        c["scenes"] += 1
        for a in run["attempts"]:
            c["attempts"] += 1
            v = a.get("violations", [])
            if not a.get("reason"):
                print(f"soak: seed {run['seed']} attempt {a['attempt']} ended without a reason")
                c["no_reason"] += 1
            for x in v:
                print(f"soak: seed {run['seed']} attempt {a['attempt']}: {x}")
            broken += (not a.get("reason")) + len(v)
            c["nonfinite"] += any("non-finite" in x for x in v)
            c["sunk"] += any("inside the ground or a tote" in x for x in v)
c["panics"] = sum(open(p).read().count("panicked") for p in glob.glob(f"{out}/{policy}-*.err"))
json.dump(c, open(f"{out}/{policy}.summary.json", "w"))
print(f"soak: {policy}: {c['scenes']} scenes, {c['attempts']} attempts, {broken} violations")
sys.exit(1 if broken else 0)
PY
  return $failed
}
sweep random "$n" || status=1
if [ "$m" -gt 0 ]; then
  if [ -f "$data/affordance/best.safetensors" ]; then
    sweep model "$m" || status=1
  else
    echo "soak: no $data/affordance/best.safetensors; run ./demo.sh first for the model scenes" >&2
    status=1
  fi
fi
if [ -n "${JSON:-}" ]; then
  python3 - "$out" "$seed" "$status" "$JSON" <<'PY'
import json, os, sys
out, seed, status, path = sys.argv[1:]
empty = dict(scenes=0, attempts=0, panics=0, no_reason=0, nonfinite=0, sunk=0)
policies = {p: json.load(open(f"{out}/{p}.summary.json")) if os.path.exists(f"{out}/{p}.summary.json") else empty
            for p in ("random", "model")}
json.dump({"seed": int(seed), "ok": status == "0", "policies": policies}, open(path, "w"), indent=1)
PY
fi
exit $status
