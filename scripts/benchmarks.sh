#!/usr/bin/env bash
# Reruns the tables of BENCHMARKS.md on this machine and prints each as Markdown, in the columns
# BENCHMARKS.md uses. Every table calls the existing tools: the release binary with its own flags,
# `graspmap bench train`, `cargo bench`, scripts/soak.sh, scripts/variants.sh,
# scripts/grasp-sweep.sh, scripts/fuzz.sh, scripts/kill-resume.sh and ./test.sh.
#
# Usage: scripts/benchmarks.sh [--quick] [TABLE...]    (no TABLE: every table, in --list order)
#        scripts/benchmarks.sh --list
#   --quick   a smoke run with tiny settings: 2 labels per object, 1 epoch, one seed per task,
#             --max-attempts 2, 2 timed bench steps, a 2 + 1 scene soak, 1 % of the fuzz cases,
#             1 kill each; its figures only show that every table runs
#   OUT=DIR   where the raw outputs go (default target/benchmarks); each table also writes
#             OUT/TABLE.md, and OUT/machine.txt records lscpu's model name and flags and the commit
#   GRASPMAP=path/to/graspmap   use that binary instead of building target/release/graspmap
#   MODEL=DIR  take the labels and best.* of DIR (e.g. data, as ./demo.sh leaves it) as the model
#             of the tables that need one, instead of labelling and training one into OUT/model
#   BF16=1    also run bf16 training and bench on a CPU without native bf16 (libtorch emulates it)
#   PEER=1    with --quick, still time the Python peer of `bench train` (full runs always do; the
#             first use installs torch into .venv-bench/, about 4.7 GB)
#
# Outcomes (labels, weights, grasps, success rates) are deterministic per machine; times are not.
# A full run takes hours on 2 cores (the variants alone about 40 minutes, the soak about 25).
set -euo pipefail
self=$(realpath "$0")
cd "$(dirname "$self")/.."
root=$(pwd)

tables=(objects pipeline threads training crop trials slurm pytorch latency workcell quality yardstick sweep placing collision
  verification centring suppression variants labelling soak faults tests webpage video)

describe() {
  case $1 in
    objects) echo "the oracle on train and test, seeds 1-3, on the bundled objects and on assets/ycb-meshes" ;;
    pipeline) echo "./demo.sh's steps timed one by one, against the Python reference" ;;
    threads) echo "an empty_bin sweep in one process with --threads 2 against two 1-thread shard processes at once" ;;
    training) echo "train --epochs 30 in fp32 and bf16: wall, seconds per epoch, images/s, best loss" ;;
    crop) echo "train --crop 64 against --crop 0 on the labels: wall, loss, train, test and empty_bin" ;;
    trials) echo "improve (collect + retrain rounds) from the labelled model, every round evaluated, vetoes on and off" ;;
    slurm) echo "a 2-shard empty_bin sweep on the one-node Slurm against one process (needs root, slurm-wlm, munge)" ;;
    pytorch) echo "graspmap bench train in bf16 and fp32: Rust against the PyTorch peer" ;;
    latency) echo "an eval attempt's wall time split into sim, render and network" ;;
    workcell) echo "cargo bench --bench workcell and one whole grasp process" ;;
    quality) echo "model, random and oracle on train, test and empty_bin, held-out seeds included" ;;
    yardstick) echo "the oracle with and without failure memory in empty_bin, against the model" ;;
    sweep) echo "scripts/grasp-sweep.sh oracle and random" ;;
    placing) echo "objects lost after a carry in empty_bin, bundled and with MESH_OBJECTS=DIR (--objects-dir)" ;;
    collision) echo "--collision-check off, walls and full without verification" ;;
    verification) echo "--verify-rejected 0, --verify-floor 0.25, --verify-square 0, the planner's rule and --verify-top 0 against the defaults" ;;
    centring) echo "--centring without verification" ;;
    suppression) echo "failure suppression's parameters against the defaults" ;;
    variants) echo "scripts/variants.sh (rgb/rgbd input, clutter labels), with the floor and held-out seeds" ;;
    labelling) echo "label from an empty data dir with --threads 1 and the default, and a byte-identical rerun" ;;
    soak) echo "scripts/soak.sh 200 20 4242: the physics invariants" ;;
    faults) echo "scripts/fuzz.sh and scripts/kill-resume.sh 10 7" ;;
    tests) echo "bash .ci/run from a fresh clone, and a clean release build" ;;
    webpage) echo "the browser test's labelling-page timings" ;;
    video) echo "one empty_bin episode without a video, as GIF and as MP4, and graspmap report" ;;
  esac
}

die() {
  echo "benchmarks: $*" >&2
  exit 2
}
log() { echo "benchmarks: $(date -u +%H:%M:%S) $*" >&2; }

quick=0
selected=()
for arg in "$@"; do
  case $arg in
    --quick) quick=1 ;;
    --list)
      for t in "${tables[@]}"; do printf '%-12s %s\n' "$t" "$(describe "$t")"; done
      exit 0
      ;;
    -h | --help)
      sed -n '2,/^set -euo/p' "$self" | sed '$d' | sed 's/^# \{0,1\}//'
      exit 0
      ;;
    -*) die "unknown option $arg (see --help)" ;;
    *)
      [[ " ${tables[*]} " == *" $arg "* ]] || die "no table '$arg'; --list names them"
      selected+=("$arg")
      ;;
  esac
done
[[ ${#selected[@]} -gt 0 ]] || selected=("${tables[@]}")

# Settings: the full run repeats BENCHMARKS.md's commands; --quick shrinks every count.
if ((quick)); then
  EPOCHS=1 PER_OBJECT=2 TEST_SEEDS=0 HELD_TEST=3000 EMPTY_SEEDS=1 HELD_EMPTY=11 MAX_ATTEMPTS=2
  ROUNDS=1 SCENES=2 ROUND_EPOCHS=1 SLURM_SEEDS=1-2 SPREAD_SEEDS= OBJECT_SEEDS=1
  BENCH_STEPS=2 BENCH_ROUNDS=1 SWEEP_SEEDS=1 SOAK_RANDOM=2 SOAK_MODEL=1 FUZZ_SCALE=0.01 KILLS=1
  VARIANT_LIST="rgb:1:2 rgbd:3:2"
else
  EPOCHS=30 PER_OBJECT=12 TEST_SEEDS=0,1000,2000 HELD_TEST=3000,4000,5000 EMPTY_SEEDS=1-10
  HELD_EMPTY=11-20 MAX_ATTEMPTS=25 BENCH_STEPS=20 BENCH_ROUNDS=2 SWEEP_SEEDS="1 2 3"
  SOAK_RANDOM=200 SOAK_MODEL=20 FUZZ_SCALE=1 KILLS=10 VARIANT_LIST="rgb:1 rgbd:1 rgb:3 rgbd:3 rgbd:3:24"
  ROUNDS=${ROUNDS:-3} SCENES=100 ROUND_EPOCHS=10 SLURM_SEEDS=1-10 OBJECT_SEEDS=1-3
  SPREAD_SEEDS=$(seq -s, 6000 1000 17000)
fi
export OBJECT_SEEDS EPOCHS PER_OBJECT TEST_SEEDS HELD_TEST EMPTY_SEEDS HELD_EMPTY MAX_ATTEMPTS ROUNDS SCENES ROUND_EPOCHS SLURM_SEEDS \
  SPREAD_SEEDS

out=$(realpath -m "${OUT:-target/benchmarks}")
mkdir -p "$out/eval" "$out/logs"
# Evaluations are shared between tables (quality, yardstick, verification, ... reuse the same runs)
# within one invocation, never across invocations: a report counts only when its .run file holds
# this run's id.
run_id="$(date +%s)-$$"

# The machine and the commit, with every table.
lscpu_out=$(lscpu 2>/dev/null || true)
cpu_model=$(sed -n 's/^Model name: *//p' <<<"$lscpu_out" | head -n 1)
cpu_flags=" $(sed -n 's/^Flags: *//p' <<<"$lscpu_out") "
has_flag() { [[ $cpu_flags == *" $1 "* ]]; }
relevant=()
has_flag avx2 && relevant+=("AVX2")
has_flag avx512f && relevant+=("AVX-512")
has_flag avx512_bf16 && relevant+=("AVX-512 BF16")
has_flag amx_bf16 && relevant+=("AMX BF16")
has_flag avx512f || relevant+=("no AVX-512")
native_bf16=0
if has_flag avx512_bf16 || has_flag amx_bf16; then native_bf16=1; fi
flag_text=$(printf '%s, ' "${relevant[@]}")
commit=$(git rev-parse --short HEAD)
if ! git diff --quiet HEAD -- src benches build.rs Cargo.toml Cargo.lock 2>/dev/null; then
  commit+=" (with uncommitted changes to the code)"
fi
BM_MACHINE="${cpu_model:-unknown CPU} (${flag_text%, }), $(nproc) cores"
BM_COMMIT=$commit
BM_QUICK=$quick
export BM_MACHINE BM_COMMIT BM_QUICK
{
  echo "model name: $cpu_model"
  echo "cores: $(nproc)"
  echo "relevant flags: ${flag_text%, }"
  echo "flags:$cpu_flags"
  echo "commit: $(git rev-parse HEAD)$([[ $commit == *uncommitted* ]] && echo ' (with uncommitted changes to the code)')"
  echo "date: $(date -u +%Y-%m-%dT%H:%M:%SZ)"
  echo "mode: $([[ $quick == 1 ]] && echo quick || echo full)"
} >"$out/machine.txt"

# libtorch (cargo bench, the scripts' own builds and ./test.sh need it), then the binary.
scripts/setup-libtorch.sh >/dev/null
if [[ -n ${GRASPMAP:-} ]]; then
  bin=$(realpath "$GRASPMAP")
else
  log "building the release binary"
  cargo build --release --locked --quiet
  bin=$root/target/release/graspmap
fi
[[ -x $bin ]] || die "no binary at $bin"

# timed FILE CMD...: runs CMD, writes its wall and CPU seconds (and exit status) to FILE as JSON,
# and returns its status.
timed() {
  local file=$1
  shift
  python3 - "$file" "$@" <<'PY'
import json, resource, subprocess, sys, time
path, cmd = sys.argv[1], sys.argv[2:]
start = time.monotonic()
status = subprocess.call(cmd)
wall = time.monotonic() - start
usage = resource.getrusage(resource.RUSAGE_CHILDREN)
with open(path, "w") as f:
    json.dump({"cmd": cmd, "wall_s": wall, "user_s": usage.ru_utime, "sys_s": usage.ru_stime,
               "status": status}, f, indent=1)
sys.exit(status)
PY
}

# eval_into FILE DATA ARGS...: one `graspmap eval` into FILE (once per invocation).
eval_into() {
  local file=$1 data=$2
  shift 2
  if [[ -f $file && -f $file.run && $(cat "$file.run") == "$run_id" ]]; then return 0; fi
  mkdir -p "$(dirname "$file")"
  rm -f "$file" "$file.run"
  log "eval $* ($(basename "$file" .json))"
  "$bin" --data "$data" --quiet --json "$file" eval "$@" >"$file.log" 2>&1 \
    || { tail -n 5 "$file.log" >&2; return 1; }
  echo "$run_id" >"$file.run"
}

# The task of each evaluation name: SPEC -> task, seeds and suppression (empty_bin also
# --max-attempts).
spec_args() {
  case $1 in
    train) spec=(--task train --seeds 0) ;;
    train13) spec=(--task train --seeds 1-3) ;;
    test) spec=(--task test --seeds "$TEST_SEEDS") ;;
    htest) spec=(--task test --seeds "$HELD_TEST") ;;
    e2) spec=(--task empty_bin --seeds 2 --n-past-action 8 --max-attempts "$MAX_ATTEMPTS") ;;
    e) spec=(--task empty_bin --seeds "$EMPTY_SEEDS" --max-attempts "$MAX_ATTEMPTS") ;;
    enp8) spec=(--task empty_bin --seeds "$EMPTY_SEEDS" --n-past-action 8 --max-attempts "$MAX_ATTEMPTS") ;;
    enp25) spec=(--task empty_bin --seeds "$EMPTY_SEEDS" --n-past-action 25 --max-attempts "$MAX_ATTEMPTS") ;;
    he) spec=(--task empty_bin --seeds "$HELD_EMPTY" --max-attempts "$MAX_ATTEMPTS") ;;
    henp8) spec=(--task empty_bin --seeds "$HELD_EMPTY" --n-past-action 8 --max-attempts "$MAX_ATTEMPTS") ;;
    *) die "no evaluation spec $1" ;;
  esac
}

# ev POLICY SPEC [TAG FLAGS...]: an evaluation of the model dir into OUT/eval/POLICY-SPEC[-TAG].json.
ev() {
  local policy=$1 name=$1-$2 spec
  spec_args "$2"
  shift 2
  if [[ $# -gt 0 ]]; then
    name+=-$1
    shift
  fi
  ensure_model
  eval_into "$out/eval/$name.json" "$model_dir" --policy "$policy" "${spec[@]}" "$@"
}

# The model the evaluation tables use: ./demo.sh's (60 default labels, 30 epochs), from this
# run's pipeline table, from MODEL=DIR, or labelled and trained into OUT/model (kept for later
# invocations of the same commit and mode).
model_dir=""
ensure_model() {
  [[ -z $model_dir ]] || return 0
  if [[ -f $out/pipeline/run && $(cat "$out/pipeline/run") == "$run_id" ]]; then
    model_dir=$out/pipeline/data
    return 0
  fi
  local dir=$out/model
  local stamp
  stamp="$(git rev-parse HEAD) binary=$(stat -c %Y "$bin") quick=$quick epochs=$EPOCHS per_object=$PER_OBJECT"
  if [[ -n ${MODEL:-} ]]; then
    stamp="copied from $(realpath "$MODEL")"
    rm -rf "$dir"
    mkdir -p "$dir/affordance"
    cp -r "$MODEL/labels" "$dir/labels"
    cp "$MODEL"/affordance/best.* "$dir/affordance/"
    echo "$stamp" >"$dir/stamp"
  elif ! [[ -f $dir/stamp && $(cat "$dir/stamp") == "$stamp" && -f $dir/affordance/best.safetensors ]]; then
    rm -rf "$dir"
    mkdir -p "$dir"
    log "model: label --per-object $PER_OBJECT and train --epochs $EPOCHS into $dir"
    "$bin" --data "$dir" --quiet --json "$dir/label.json" label --per-object "$PER_OBJECT" >"$dir/label.log" 2>&1
    "$bin" --data "$dir" --quiet --json "$dir/train.json" train --epochs "$EPOCHS" >"$dir/train.log" 2>&1
    echo "$stamp" >"$dir/stamp"
  fi
  model_dir=$dir
}

# ---------------------------------------------------------------------------------------------
# The tables: each runs its commands, then render prints its Markdown.

t_pipeline() {
  local d=$out/pipeline
  rm -rf "$d"
  mkdir -p "$d/times"
  local data=$d/data
  local start=$SECONDS
  log "pipeline: ./demo.sh's steps into $data"
  timed "$d/times/label.json" "$bin" --data "$data" --quiet --json "$d/label.json" label \
    --per-object "$PER_OBJECT" >"$d/label.log" 2>&1
  timed "$d/times/train.json" "$bin" --data "$data" --quiet --json "$d/train.json" train \
    --epochs "$EPOCHS" >"$d/train.log" 2>&1
  timed "$d/times/eval_train.json" "$bin" --data "$data" --quiet --json "$d/eval_train.json" eval \
    --task train >"$d/eval_train.log" 2>&1
  timed "$d/times/eval_test.json" "$bin" --data "$data" --quiet --json "$d/eval_test.json" eval \
    --task test >"$d/eval_test.log" 2>&1
  timed "$d/times/eval_empty_bin.json" "$bin" --data "$data" --quiet --json "$d/eval_empty_bin.json" \
    eval --task empty_bin --n-past-action 8 --max-attempts "$MAX_ATTEMPTS" \
    --record "$d/empty_bin.mp4" >"$d/eval_empty_bin.log" 2>&1
  timed "$d/times/report.json" "$bin" --data "$data" --quiet --json "$d/report.json" report \
    >"$d/report.log" 2>&1
  echo "{\"wall_s\": $((SECONDS - start))}" >"$d/times/total.json"
  echo "$run_id" >"$d/run"
}

t_training() {
  local d=$out/training precision
  rm -rf "$d"
  mkdir -p "$d"
  ensure_labels
  for precision in fp32 bf16; do
    if [[ $precision == bf16 && $native_bf16 == 0 && ${BF16:-0} != 1 ]]; then
      echo "no native bf16 on this CPU (BF16=1 runs it emulated)" >"$d/bf16.skipped"
      continue
    fi
    mkdir -p "$d/$precision"
    cp -r "$labels_dir" "$d/$precision/labels"
    log "training: train --epochs $EPOCHS --precision $precision"
    "$bin" --data "$d/$precision" --quiet --json "$d/$precision/train.json" train --epochs "$EPOCHS" \
      --precision "$precision" >"$d/$precision/train.log" 2>&1
  done
}

t_crop() {
  local d=$out/crop crop name spec
  rm -rf "$d"
  ensure_labels
  for crop in 0 64; do
    mkdir -p "$d/$crop"
    cp -r "$labels_dir" "$d/$crop/labels"
    log "crop: train --epochs $EPOCHS --crop $crop"
    "$bin" --data "$d/$crop" --quiet --json "$d/$crop/train.json" train --epochs "$EPOCHS" \
      --crop "$crop" >"$d/$crop/train.log" 2>&1
    for name in train test enp8; do
      spec_args "$name"
      eval_into "$d/$crop/eval-$name.json" "$d/$crop" "${spec[@]}"
    done
  done
}

# The loop from the default model (labels and crops), then every round's model and the start
# model on train, test and empty_bin (held-out seeds too), with the vetoes and as the plain
# argmax; the oracle with memory beside them, and the spread of test between seed sets.
t_trials() {
  local d=$out/trials name spec tag ck
  ensure_model
  if ! [[ -f $d/run && $(cat "$d/run") == "$run_id" ]]; then
    rm -rf "$d"
    mkdir -p "$d/data/affordance"
    cp -r "$model_dir/labels" "$d/data/labels"
    cp "$model_dir"/affordance/best.* "$d/data/affordance/"
    log "trials: improve --rounds $ROUNDS --scenes $SCENES --epochs $ROUND_EPOCHS"
    timed "$d/improve.time.json" "$bin" --data "$d/data" --quiet --json "$d/improve.json" improve \
      --rounds "$ROUNDS" --scenes "$SCENES" --epochs "$ROUND_EPOCHS" >"$d/improve.log" 2>&1
    echo "$run_id" >"$d/run"
  fi
  for tag in start $(seq -f 'round_%02g' 1 "$ROUNDS"); do
    if [[ $tag == start ]]; then ck=$d/data/affordance/best.safetensors; else ck=$d/data/improve/$tag/model/best.safetensors; fi
    for name in train test htest enp8 henp8; do
      spec_args "$name"
      eval_into "$d/eval/$tag-$name.json" "$d/data" --checkpoint "$ck" "${spec[@]}"
      eval_into "$d/eval/$tag-$name-argmax.json" "$d/data" --checkpoint "$ck" "${spec[@]}" \
        --verify-top 0 --collision-check off
    done
    for name in enp8 henp8; do
      spec_args "$name"
      eval_into "$d/eval/$tag-$name-giveup6.json" "$d/data" --checkpoint "$ck" "${spec[@]}" --give-up-after 6
      eval_into "$d/eval/$tag-$name-nopush.json" "$d/data" --checkpoint "$ck" "${spec[@]}" --push-unverified false
    done
  done
  # The last round with the checks as they were before pushing and the 3 mm squeeze margin.
  tag=$(printf 'round_%02d' "$ROUNDS")
  ck=$d/data/improve/$tag/model/best.safetensors
  for name in test htest enp8 henp8; do
    spec_args "$name"
    eval_into "$d/eval/$tag-$name-before.json" "$d/data" --checkpoint "$ck" "${spec[@]}" \
      --push-unverified false --verify-margin 6
  done
  ev oracle train
  ev oracle test
  ev oracle htest
  ev oracle enp8
  ev oracle henp8
  ev oracle enp8 giveup6 --give-up-after 6
  ev oracle henp8 giveup6 --give-up-after 6
  # How far apart two sets of three test seeds fall on their own: test and held-out test of the
  # labels-only model, the last round and the oracle, with more seeds (SPREAD_SEEDS) beside them.
  [[ -n $SPREAD_SEEDS ]] || return 0
  eval_into "$d/eval/start-spread.json" "$d/data" --checkpoint "$d/data/affordance/best.safetensors" \
    --task test --seeds "$SPREAD_SEEDS"
  eval_into "$d/eval/last-spread.json" "$d/data" --checkpoint "$ck" --task test --seeds "$SPREAD_SEEDS"
  eval_into "$out/eval/oracle-spread.json" "$model_dir" --policy oracle --task test --seeds "$SPREAD_SEEDS"
}

t_slurm() {
  local d=$out/slurm conf
  rm -rf "$d"
  mkdir -p "$d/data"
  conf=$(scripts/slurm/local-cluster.sh start "$d/cluster") || die "the one-node Slurm did not start (needs root, slurm-wlm and munge)"
  local sweep=(eval --task empty_bin --policy oracle --seeds "$SLURM_SEEDS" --n-past-action 8 --max-attempts "$MAX_ATTEMPTS")
  log "slurm: ${sweep[*]} in one process, then in 2 shards under Slurm"
  timed "$d/single.time.json" "$bin" --data "$d/data" --quiet --threads 2 --json "$d/single.json" "${sweep[@]}" >"$d/single.log" 2>&1
  python3 - "$d" "$conf" "$bin" "${sweep[@]}" <<'PY'
import json, os, subprocess, sys, time
d, conf, binary, sweep = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:]
env = dict(os.environ, SLURM_CONF=conf, RUN_DIR=f"{d}/run", DATA=f"{d}/data", SHARDS="2",
           CPUS_PER_TASK="1", MEM_PER_TASK="2G", GRASPMAP=binary)
start = time.monotonic()
subprocess.run(["scripts/slurm/submit.sh", *sweep], env=env, check=True, stdout=subprocess.DEVNULL)
jobs = dict(l.split("=", 1) for l in open(f"{d}/run/jobs.env").read().split())
while True:
    out = subprocess.run(["scontrol", "show", "job", jobs["MERGE_JOB"], "--oneliner"], env=env,
                         capture_output=True, text=True).stdout
    state = next((f.split("=", 1)[1] for f in out.split() if f.startswith("JobState=")), "UNKNOWN")
    if state not in ("PENDING", "RUNNING", "CONFIGURING", "COMPLETING"):
        break
    time.sleep(0.2)
wall = time.monotonic() - start
shards = [json.load(open(f"{d}/run/shard_{i}.json"))["results"]["timing"]["total_wall"] for i in (1, 2)]
json.dump({"state": state, "wall_s": wall, "shard_walls": shards}, open(f"{d}/slurm.time.json", "w"))
PY
  scripts/slurm/local-cluster.sh stop "$d/cluster"
}

t_objects() {
  local d=$out/objects set dir task
  mkdir -p "$d"
  for set in bundled meshes; do
    dir=()
    [[ $set == meshes ]] && dir=(--objects-dir "$root/assets/ycb-meshes")
    for task in train test; do
      eval_into "$d/$set-$task.json" "$d/data-$set" --policy oracle --task "$task" --seeds "$OBJECT_SEEDS" "${dir[@]}"
    done
  done
}

t_threads() {
  local d=$out/threads
  rm -rf "$d"
  mkdir -p "$d"
  ensure_model
  local sweep=(eval --task empty_bin --seeds "$EMPTY_SEEDS" --n-past-action 8 --max-attempts "$MAX_ATTEMPTS")
  cp -r "$model_dir" "$d/one"
  log "threads: ${sweep[*]} with --threads 2 in one process"
  timed "$d/one.time.json" "$bin" --data "$d/one" --quiet --threads 2 --json "$d/one.json" "${sweep[@]}" >"$d/one.log" 2>&1
  log "threads: the same sweep as two 1-thread shard processes at once"
  cp -r "$model_dir" "$d/two"
  python3 - "$d" "$bin" "${sweep[@]}" <<'PY'
import json, subprocess, sys, time
d, binary, sweep = sys.argv[1], sys.argv[2], sys.argv[3:]
start = time.monotonic()
procs = [subprocess.Popen([binary, "--data", f"{d}/two", "--quiet", "--threads", "1", "--json",
                           f"{d}/shard_{i}.json", *sweep, "--shard", f"{i}/2"],
                          stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL) for i in (1, 2)]
ends = []
for p in procs:
    if p.wait() != 0:
        sys.exit(f"threads: a shard failed with status {p.returncode}")
    ends.append(time.monotonic() - start)
json.dump({"wall_s": max(ends), "shard_walls": ends}, open(f"{d}/two.time.json", "w"))
PY
}

# Labels for the training table: the model's when it was labelled in this run, else label anew.
labels_dir=""
ensure_labels() {
  [[ -z $labels_dir ]] || return 0
  if [[ -f $out/pipeline/run && $(cat "$out/pipeline/run") == "$run_id" ]]; then
    labels_dir=$out/pipeline/data/labels
    return 0
  fi
  local dir=$out/training-labels
  rm -rf "$dir"
  "$bin" --data "$dir" --quiet label --per-object "$PER_OBJECT" >"$out/logs/training-labels.log" 2>&1
  labels_dir=$dir/labels
}

t_pytorch() {
  local d=$out/bench precision peer=()
  mkdir -p "$d"
  rm -f "$d"/*.json "$d"/*.skipped
  if ((quick)) && [[ ${PEER:-0} != 1 ]]; then peer=(--no-peer); fi
  for precision in bf16 fp32; do
    if [[ $precision == bf16 && $native_bf16 == 0 && ${BF16:-0} != 1 ]]; then
      echo "no native bf16 on this CPU (BF16=1 runs it emulated)" >"$d/bf16.skipped"
      continue
    fi
    log "pytorch: bench train --precision $precision"
    "$bin" --quiet --json "$d/$precision.json" bench train --precision "$precision" \
      --steps "$BENCH_STEPS" --rounds "$BENCH_ROUNDS" "${peer[@]}" >"$d/$precision.log" 2>&1
  done
}

t_latency() {
  ev model enp8
  ev model train
  ev model test
}

t_workcell() {
  local d=$out/workcell
  mkdir -p "$d"
  log "workcell: cargo bench --bench workcell"
  cargo bench --locked --bench workcell >"$d/bench.log" 2>"$d/bench.err"
  timed "$d/grasp.json" "$bin" --quiet grasp --object YcbPowerDrill --seed 2 --oracle >"$d/grasp.log" 2>&1
}

t_quality() {
  local spec
  for spec in train test e2 e enp8 htest henp8; do ev model "$spec"; done
  for spec in train test e; do ev random "$spec"; done
  for spec in train test e enp8 henp8; do ev oracle "$spec"; done
}

t_yardstick() {
  local spec
  for spec in e enp8 enp25 he henp8; do ev oracle "$spec"; done
  ev model enp8
  ev model henp8
}

# MESH_OBJECTS=DIR: an objects dir (with split.json) holding mesh models, for the second column.
t_placing() {
  local policy
  for policy in model oracle; do
    ev "$policy" enp8
    ev "$policy" train13
    if [[ -n ${MESH_OBJECTS:-} ]]; then
      ev "$policy" enp8 mesh --objects-dir "$(realpath "$MESH_OBJECTS")"
      ev "$policy" train13 mesh --objects-dir "$(realpath "$MESH_OBJECTS")"
    fi
  done
}

t_sweep() {
  local d=$out/sweep policy
  mkdir -p "$d"
  for policy in oracle random; do
    log "sweep: scripts/grasp-sweep.sh $policy $SWEEP_SEEDS"
    # shellcheck disable=SC2086 # the seeds are separate arguments
    scripts/grasp-sweep.sh "$policy" $SWEEP_SEEDS >"$d/$policy.log" 2>"$d/$policy.err"
  done
}

t_collision() {
  local spec check
  for spec in train test e enp8; do
    ev model "$spec" vt0 --verify-top 0
    for check in off walls; do
      ev model "$spec" "vt0-cc$check" --verify-top 0 --collision-check "$check"
    done
  done
}

t_verification() {
  local spec
  for spec in train test enp8 henp8; do
    ev model "$spec"
    ev model "$spec" vr0 --verify-rejected 0
    ev model "$spec" vf25 --verify-floor 0.25
    ev model "$spec" sq0 --verify-square 0
    ev model "$spec" planner --verify-strips 2 --verify-square 0
    ev model "$spec" vt0 --verify-top 0
    ev model "$spec" m6 --verify-margin 6
    ev model "$spec" nopush --push-unverified false
  done
}

t_centring() {
  local spec
  for spec in train test enp8; do
    ev model "$spec" vt0 --verify-top 0
    ev model "$spec" vt0-centring --verify-top 0 --centring
  done
}

t_suppression() {
  ev model enp8
  ev model enp8 reach1 --suppress-rotation-reach 1
  ev model enp8 reach4 --suppress-rotation-reach 4
  ev model enp8 sigma6 --suppression-sigma 6
  ev model enp8 successes --suppress-successes
  ev model e
}

t_variants() {
  local d=$out/variants v name input clutter per rows="" first=""
  log "variants: scripts/variants.sh with VARIANTS=\"$VARIANT_LIST\""
  GRASPMAP=$bin VARIANTS=$VARIANT_LIST EXTRA=0 EPOCHS=$EPOCHS TEST_SEEDS=$TEST_SEEDS \
    EMPTY_SEEDS=$EMPTY_SEEDS scripts/variants.sh "$d" >"$out/logs/variants.md" 2>"$out/logs/variants.err"
  # The floor and the held-out seeds, for the default and for rgbd with clutter 3 (the rows of
  # BENCHMARKS.md); variants.sh wrote the rest into DIR/eval/.
  for v in $VARIANT_LIST; do
    IFS=: read -r input clutter per <<<"$v"
    name="$input-c$clutter${per:+-p$per}"
    local label="$input, clutter $clutter" shown
    [[ -z $per ]] || label+=", $per per object"
    shown=$label
    [[ -n $first ]] || { first=$name && shown+=" (default)"; }
    rows+="$name|$shown|0;"
    if [[ $name == "$first" || ($input == rgbd && $clutter == 3 && -z ${per:-}) ||
      ($quick == 1 && $input == rgbd && $clutter == 3) ]]; then
      local e=$d/$name/eval spec
      spec_args htest
      eval_into "$e/htest.json" "$d/$name" "${spec[@]}"
      spec_args henp8
      eval_into "$e/henp8.json" "$d/$name" "${spec[@]}"
      for spec_name in train test enp8 htest henp8; do
        spec_args "$spec_name"
        eval_into "$e/$spec_name-vf25.json" "$d/$name" "${spec[@]}" --verify-floor 0.25
      done
      rows+="$name|$label, floor 0.25|0.25;"
    fi
  done
  echo "$rows" >"$d/rows.txt"
}

t_labelling() {
  local d=$out/labelling
  rm -rf "$d"
  mkdir -p "$d"
  log "labelling: label with --threads 1, then with the default"
  "$bin" --data "$d/one" --quiet --threads 1 --json "$d/one.json" label --per-object "$PER_OBJECT" \
    >"$d/one.log" 2>&1
  "$bin" --data "$d/default" --quiet --json "$d/default.json" label --per-object "$PER_OBJECT" \
    >"$d/default.log" 2>&1
  if diff -r -x .lock "$d/one/labels" "$d/default/labels" >"$d/diff.txt"; then
    echo identical >"$d/rerun.txt"
  else
    echo different >"$d/rerun.txt"
  fi
}

t_soak() {
  local d=$out/soak status=0
  rm -rf "$d"
  mkdir -p "$d"
  ensure_model
  log "soak: scripts/soak.sh $SOAK_RANDOM $SOAK_MODEL 4242"
  GRASPMAP=$bin DATA=$model_dir timed "$d/times.json" scripts/soak.sh "$SOAK_RANDOM" "$SOAK_MODEL" 4242 \
    >"$d/soak.log" 2>"$d/soak.err" || status=$?
  echo "$status" >"$d/status"
  local reports
  reports=$(sed -n 's/.*reports in \(.*\)$/\1/p' "$d/soak.err" | head -n 1)
  [[ -z $reports || ! -d $reports ]] || cp -r "$reports" "$d/reports"
}

t_faults() {
  local d=$out/faults
  rm -rf "$d"
  mkdir -p "$d"
  log "faults: scripts/fuzz.sh $FUZZ_SCALE"
  timed "$d/fuzz.time.json" scripts/fuzz.sh "$FUZZ_SCALE" >"$d/fuzz.log" 2>"$d/fuzz.err" || true
  log "faults: scripts/kill-resume.sh $KILLS 7"
  timed "$d/kill.time.json" scripts/kill-resume.sh "$KILLS" 7 >"$d/kill.log" 2>"$d/kill.err" || true
}

t_tests() {
  local d=$out/tests tmp
  rm -rf "$d"
  mkdir -p "$d"
  if ((quick)); then
    # A smoke run: one test through ./test.sh in this checkout, no fresh clone, no clean build.
    log "tests: ./test.sh matmul_on_cpu (quick)"
    timed "$d/test.time.json" ./test.sh matmul_on_cpu >"$d/test.log" 2>&1
    return 0
  fi
  tmp=$(mktemp -d)
  # shellcheck disable=SC2064 # the path is fixed now
  trap "rm -rf '$tmp'" EXIT
  git clone -q "$root" "$tmp/clone"
  log "tests: ./test.sh and scripts/install-check.sh (= .ci/run) in a fresh clone"
  (cd "$tmp/clone" && timed "$d/test.time.json" ./test.sh) >"$d/test.log" 2>&1
  (cd "$tmp/clone" && timed "$d/install.time.json" scripts/install-check.sh) >"$d/install.log" 2>&1
  log "tests: a clean cargo build --release --locked of git archive HEAD"
  mkdir -p "$tmp/export"
  git archive HEAD | tar -x -C "$tmp/export"
  (cd "$tmp/export" && scripts/setup-libtorch.sh >/dev/null &&
    timed "$d/build.time.json" cargo build --release --locked) >"$d/build.log" 2>&1
}

t_webpage() {
  local d=$out/webpage timings=$root/target/browser/label-timings.json
  mkdir -p "$d"
  rm -f "$timings" "$d/label-timings.json"
  log "webpage: the browser test through ./test.sh"
  ./test.sh a_person_labels_a_small_dataset_in_the_browser_with_mouse_and_keys_only >"$d/test.log" 2>&1
  cp "$timings" "$d/label-timings.json"
}

t_video() {
  local d=$out/video kind
  rm -rf "$d"
  mkdir -p "$d"
  ensure_model
  for kind in none gif mp4; do
    local record=()
    [[ $kind == none ]] || record=(--record "$d/ep.$kind")
    log "video: eval --task empty_bin --seeds 1 ${record[*]}"
    GRASPMAP_LOG=debug timed "$d/$kind.time.json" "$bin" --data "$model_dir" --quiet \
      --json "$d/$kind.json" eval --task empty_bin --seeds 1 --max-attempts "$MAX_ATTEMPTS" \
      "${record[@]}" >"$d/$kind.log" 2>&1
    if [[ $kind != none ]] && command -v ffprobe >/dev/null; then
      ffprobe -v error -select_streams v:0 -count_frames \
        -show_entries stream=codec_name,nb_read_frames,duration -of json "$d/ep.$kind" \
        >"$d/$kind.probe.json" 2>/dev/null || true
    fi
  done
  timed "$d/report.time.json" "$bin" --data "$model_dir" --quiet --json "$d/report.json" report \
    --out "$d/report.html" >"$d/report.log" 2>&1
}

# ---------------------------------------------------------------------------------------------
# render TABLE: prints the table's Markdown from OUT (and keeps it in OUT/TABLE.md).
render() {
  python3 - "$1" "$out" >"$out/$1.md" <<'PY' || return 1
import glob, json, math, os, re, statistics, sys

table, out = sys.argv[1], sys.argv[2]
E = os.environ
DASH = "–"
QUICK = E.get("BM_QUICK") == "1"


def load(path):
    """The `results` of a JSON report (or the whole file); None when missing or unreadable."""
    try:
        with open(path) as f:
            data = json.load(f)
    except (OSError, ValueError):
        return None
    return data.get("results", data) if isinstance(data, dict) else data


def ev(name, base=None):
    r = load(f"{base or out + '/eval'}/{name}.json")
    return None if r is None or r.get("interrupted") else r


def seeds(text):
    return "seeds " + text.replace("-", "–").replace(",", ", ")


def minus(text):
    return text.replace("-", "−")


def pct(x):
    return f"{100 * x:.1f}"


def rate(r, ci=False):
    if r is None:
        return DASH
    s = r["success"]
    text = f"{s['successes']}/{s['trials']} = {pct(s['rate'])} %"
    return text + (f" (CI {pct(s['wilson_low'])}–{pct(s['wilson_high'])})" if ci else "")


def count(r):
    if r is None:
        return DASH
    s = r["success"]
    return f"{s['successes']}/{s['trials']}"


def moved(r, span=True, lost=True):
    if r is None or r.get("moved") is None:
        return DASH
    m = r["moved"]
    text = f"{m['mean']:.1f} ± {m['std']:.1f}"
    if span and m["count"] > 1:
        text += f" ({m['min']:.0f}–{m['max']:.0f})"
    if lost:
        text += f", {r['lost']['mean']:.1f} lost"
    return text


def scene(r):
    """One empty_bin scene: k/n moved, l lost."""
    if r is None or not r["runs"] or r["runs"][0].get("bin") is None:
        return DASH
    b = r["runs"][0]["bin"]
    return f"{b['moved']}/{len(b['locations'])} moved, {b['lost']} lost"


def per_seed(r):
    """Successes (train/test) or objects moved (empty_bin) per base seed, in seed order."""
    if r is None:
        return None
    counts = {s: 0 for s in r["seeds"]}
    for run in r["runs"]:
        if run.get("bin") is not None:
            counts[run["seed"]] = run["bin"]["moved"]
        else:
            counts[run["seed"]] += sum(a["success"] for a in run["attempts"])
    return [counts[s] for s in r["seeds"]]


def paired(a, b):
    """Mean ± standard error of the per-seed differences a − b."""
    a, b = per_seed(a), per_seed(b)
    if not a or not b or len(a) != len(b):
        return DASH
    d = [x - y for x, y in zip(a, b)]
    mean = sum(d) / len(d)
    se = (statistics.stdev(d) / math.sqrt(len(d))) if len(d) > 1 else 0.0
    return minus(f"{mean:+.2f}") + f" ± {se:.2f}"


def secs(x):
    return DASH if x is None else f"{x:.2f} s" if x < 10 else f"{x:.1f} s"


def wall(path):
    t = load(path)
    return None if t is None else t.get("wall_s")


def md(header, rows):
    print("| " + " | ".join(header) + " |")
    print("|" + "---|" * len(header))
    for row in rows:
        print("| " + " | ".join(str(c) for c in row) + " |")
    print()


MACHINE, COMMIT = E["BM_MACHINE"], E["BM_COMMIT"]


def head(title, command):
    print(f"### {title}")
    print()
    mode = " (`--quick`: a smoke run, not comparable)" if QUICK else ""
    print(f"{MACHINE}; commit {COMMIT}{mode}. {command}")
    print()


def t_objects():
    d = f"{out}/objects"
    head("Bundled objects against the reference's meshes",
         f"`graspmap eval --policy oracle --task T --seeds {E['OBJECT_SEEDS']} [--objects-dir assets/ycb-meshes]`.")
    rows, widest = [], 0
    for task in ("train", "test"):
        a, b = load(f"{d}/bundled-{task}.json"), load(f"{d}/meshes-{task}.json")
        if a is None or b is None:
            raise SystemExit(f"objects: missing {d}/bundled-{task}.json or {d}/meshes-{task}.json")
        pb = {o["object"]: o for o in b["per_object"]}
        for o in a["per_object"]:
            other = pb[o["object"]]
            widest = max(widest, abs(o["successes"] - other["successes"]))
            rows.append([task, o["object"], f"{o['successes']}/{o['attempts']}", f"{other['successes']}/{other['attempts']}"])
        rows.append([task, "**all**", rate(a), rate(b)])
        rows.append([task, "sim per attempt", secs(a["timing"]["mean"]["sim"]), secs(b["timing"]["mean"]["sim"])])
    md(["task", "object", "bundled primitives", "`--objects-dir assets/ycb-meshes`"], rows)
    print(f"Largest difference on one object: {widest} attempts.")
    print()


def t_threads():
    d = f"{out}/threads"
    head("Two threads in one process against two processes",
         f"`graspmap eval --task empty_bin --seeds {E['EMPTY_SEEDS']} --n-past-action 8` with `--threads 2`, against the "
         "same sweep as `--shard 1/2` and `--shard 2/2` with `--threads 1`, both started at once.")
    one, two = load(f"{d}/one.time.json"), load(f"{d}/two.time.json")
    shards = [load(f"{d}/shard_{i}.json") for i in (1, 2)]
    whole = load(f"{d}/one.json")
    if None in (one, two, whole) or None in shards:
        raise SystemExit(f"threads: a report or timing under {d} is missing")
    per = lambda r: r["timing"]["mean"]
    md(["run", "wall", "attempts", "wall per attempt", "network per attempt"], [
        ["one process, `--threads 2`", secs(one["wall_s"]), whole["timing"]["attempts"],
         secs(one["wall_s"] / whole["timing"]["attempts"]), secs(per(whole)["network"])],
        ["two processes, `--threads 1` each", secs(two["wall_s"]),
         sum(s["timing"]["attempts"] for s in shards),
         secs(two["wall_s"] / sum(s["timing"]["attempts"] for s in shards)),
         " / ".join(secs(per(s)["network"]) for s in shards)],
    ])
    print(f"Ratio, one process over two: **{one['wall_s'] / two['wall_s']:.2f}**.")
    print()


def t_pipeline():
    d = f"{out}/pipeline"
    head("Pipeline against the Python reference",
         "`./demo.sh`'s steps: label, train, eval train, test, empty_bin --n-past-action 8 --record, report.")
    ev_walls = ", ".join(secs(wall(f"{d}/times/eval_{t}.json")) for t in ("train", "test", "empty_bin"))
    md(["machine", "commit", "labels", f"training, {E['EPOCHS']} epochs",
        "evals: train, test, empty_bin with video", "pipeline"],
       [[MACHINE, COMMIT, secs(wall(f"{d}/times/label.json")), secs(wall(f"{d}/times/train.json")),
         ev_walls, f"**{secs(wall(f'{d}/times/total.json'))}** (report {secs(wall(f'{d}/times/report.json'))})"],
        ["Python reference", DASH, DASH, DASH, DASH, "about 15 min (quoted in BENCHMARKS.md, not measured)"]])


def t_training():
    d = f"{out}/training"
    head("Training", f"`graspmap --data D train --epochs {E['EPOCHS']} --precision P` on a copy of the labels.")
    rows = []
    for p in ("fp32", "bf16"):
        if os.path.exists(f"{d}/{p}.skipped"):
            rows.append([MACHINE, COMMIT, p, "not run: " + open(f"{d}/{p}.skipped").read().strip(),
                         DASH, DASH, DASH])
            continue
        r = load(f"{d}/{p}/train.json")
        if r is None:
            rows.append([MACHINE, COMMIT, p, "failed (see the log)", DASH, DASH, DASH])
            continue
        per_epoch = []
        try:
            with open(f"{d}/{p}/affordance/losses.csv") as f:
                next(f)
                per_epoch = [float(line.split(",")[4]) for line in f if line.strip()]
        except (OSError, StopIteration, IndexError, ValueError):
            pass
        later = per_epoch[1:] or per_epoch
        span = f"{min(later):.2f}–{max(later):.2f}" if later else DASH
        images = r["train_samples"] + r["val_samples"]
        speed = f"≈ {images / statistics.median(later):.1f}" if later else DASH
        rows.append([MACHINE, COMMIT, p, f"{r['wall_seconds']:.1f} s", span, speed,
                     f"{r['best_val_loss']:.5f} ({r['best_epoch']})"])
    md(["machine", "commit", "precision", f"{E['EPOCHS']} epochs, wall", "s per epoch after the first",
        "images/s", "best validation loss (epoch)"], rows)


def t_pytorch():
    d = f"{out}/bench"
    head("Rust against PyTorch", "`graspmap bench train --precision P` (Rust and the Python peer alternating).")
    rows, ratios = [], []
    for p in ("bf16", "fp32"):
        r = load(f"{d}/{p}.json")
        if r is None:
            rows.append([p, DASH, "not run" if os.path.exists(f"{d}/{p}.skipped") else "failed", DASH, DASH])
            continue
        for side in ("rust", "python"):
            s = r.get(side)
            if s:
                rows.append([p, "Rust" if side == "rust" else "Python", f"{s['train_step_ms']:.1f}",
                             f"{s['train_images_per_s']:.2f}", f"{s['infer_8_rotations_ms']:.1f}"])
        if r.get("train_ratio") is not None:
            ratios.append(f"{p}: training {r['train_ratio']:.2f}×, inference {r['infer_ratio']:.2f}×")
    md(["precision", "side", "train ms/step", "train images/s", "8-rotation inference ms"], rows)
    print("Rust/Python: " + ("; ".join(ratios) if ratios else "no peer run") + ".")
    print()


def t_latency():
    head("Attempt latency", "`results.timing` of the model's evaluations.")
    rows = []
    for name, what in (("model-enp8", f"empty_bin, model, np8, {seeds(E['EMPTY_SEEDS'])}"),
                       ("model-train", "train, model"), ("model-test", "test, model")):
        r = ev(name)
        if r is None:
            rows.append([MACHINE, COMMIT, what, DASH, DASH, DASH, DASH, DASH, DASH])
            continue
        t = r["timing"]
        m = t["mean"]
        rows.append([MACHINE, COMMIT, f"{what}, mean of {t['attempts']}", f"{m['wall']:.2f} s",
                     f"{m['sim']:.2f} s", f"{m['render']:.3f} s", f"{m['network']:.2f} s",
                     str(t.get("workers", 1)), f"{t['total_wall'] / max(t['attempts'], 1):.2f} s"])
    md(["machine", "commit", "attempt", "wall", "sim", "render", "network", "at once",
        "run's wall / attempts"], rows)


def t_workcell():
    d = f"{out}/workcell"
    head("Workcell speed", "`cargo bench --bench workcell`, and one whole `graspmap grasp` process.")
    try:
        text = open(f"{d}/bench.log").read()
    except OSError:
        text = ""
    frame = re.search(r"render 128x128, (\d+) drawables.*?: median ([\d.]+) ms", text)
    pick = re.search(r"pick attempt .*?, (\d+) attempts: median (\d+) ms, mean (\d+) ms, max (\d+) ms; "
                     r"([\d.]+) simulated s per attempt", text)
    rows = [["one 128 × 128 top-down frame" + (f", {frame.group(1)} drawables" if frame else ""),
             f"{frame.group(2)} ms, median" if frame else DASH]]
    if pick:
        n, med, mean, mx, sim = pick.groups()
        rows.append([f"one single-object pick attempt, {n} attempts", f"{med} ms median, {mean} ms mean, {mx} ms max"])
        rows.append(["simulated time per attempt",
                     f"{float(sim):.1f} s (≈ {float(sim) / (float(mean) / 1e3):.0f}× faster than real time)"])
    else:
        rows.append(["one single-object pick attempt", DASH])
    rows.append(["`graspmap grasp --object YcbPowerDrill --seed 2 --oracle`, whole process",
                 f"{secs(wall(f'{d}/grasp.json'))} wall"])
    rows.append(["the Python reference, one single-object pick attempt", "about 1.6 s (quoted in BENCHMARKS.md)"])
    md(["what", "figure"], rows)


def t_quality():
    head("Quality: model, random and oracle", "`graspmap eval --task T --seeds S [--n-past-action 8] [--policy P]`.")
    ref = {"train": "> 70 % (93 %)", "test": "≈ 50 % (68 %; 100 % with retries)",
           "e2": "at least 8 of 15 moved (15/15)"}
    m, r, o = (lambda n: ev("model-" + n)), (lambda n: ev("random-" + n)), (lambda n: ev("oracle-" + n))
    md(["task", "model", "random", "oracle", "reference (best student runs)"], [
        ["train, seed 0", rate(m("train"), True), rate(r("train")), rate(o("train")), ref["train"]],
        [f"test, {seeds(E['TEST_SEEDS'])}", rate(m("test"), True), rate(r("test")), rate(o("test"), True), ref["test"]],
        ["empty_bin, seed 2, np8", scene(m("e2")), DASH, DASH, ref["e2"]],
        [f"empty_bin, {seeds(E['EMPTY_SEEDS'])}", moved(m("e")), moved(r("e"), span=False, lost=False), moved(o("e")), DASH],
        [f"empty_bin, {seeds(E['EMPTY_SEEDS'])}, np8", f"**{moved(m('enp8'))}**", DASH, moved(o("enp8")), DASH],
        [f"held out: test, {seeds(E['HELD_TEST'])}", rate(m("htest")), DASH, DASH, DASH],
        [f"held out: empty_bin, {seeds(E['HELD_EMPTY'])}, np8", moved(m("henp8")), DASH, moved(o("henp8")), DASH],
    ])


def t_yardstick():
    head("Oracle yardstick in clutter", "`graspmap eval --task empty_bin --policy oracle --seeds S [--n-past-action N]`.")
    a, b = seeds(E["EMPTY_SEEDS"]), seeds(E["HELD_EMPTY"])
    md(["policy", f"empty_bin, {a}", "pick success", f"empty_bin, {b}", "pick success"], [
        ["oracle, no memory", moved(ev("oracle-e"), lost=False), count(ev("oracle-e")),
         moved(ev("oracle-he"), lost=False), count(ev("oracle-he"))],
        ["oracle, np8", moved(ev("oracle-enp8"), lost=False), count(ev("oracle-enp8")),
         moved(ev("oracle-henp8"), lost=False), count(ev("oracle-henp8"))],
        ["oracle, `--n-past-action 25` (the whole episode)", moved(ev("oracle-enp25"), lost=False),
         count(ev("oracle-enp25")), DASH, DASH],
        ["model, np8", moved(ev("model-enp8"), lost=False), count(ev("model-enp8")),
         moved(ev("model-henp8"), lost=False), count(ev("model-henp8"))],
    ])
    print(f"Oracle np8 minus model np8, paired per seed: {paired(ev('oracle-enp8'), ev('model-enp8'))} ({a}), "
          f"{paired(ev('oracle-henp8'), ev('model-henp8'))} ({b}).")
    print()


def after_carry(r):
    """Per scene: objects lost, and those lost after a successful carry (placed outside bin 2)."""
    if r is None or r.get("lost") is None:
        return DASH
    carried = [a for run in r["runs"] for a in run["attempts"] if a.get("success")]
    outside = sum(1 for a in carried if a.get("placed") != "bin2")
    return f"{r['lost']['mean']:.1f} lost, {outside / len(r['runs']):.1f} after a carry"


def t_placing():
    head("Objects that stay in bin 2",
         "`graspmap eval --task empty_bin --seeds S --n-past-action 8 [--policy oracle] [--objects-dir MESH_OBJECTS]`.")
    rows = []
    for policy in ("model", "oracle"):
        for tag, objects in (("", "bundled"), ("-mesh", "MESH_OBJECTS")):
            e, t = ev(f"{policy}-enp8{tag}"), ev(f"{policy}-train13{tag}")
            rows.append([policy, objects, moved(e, lost=False), after_carry(e), rate(t)])
    md(["policy", "objects", f"empty_bin, {seeds(E['EMPTY_SEEDS'])}, np8: moved", "lost per scene", "train, seeds 1–3"], rows)


def t_sweep():
    d = f"{out}/sweep"
    head("Oracle sweep", "`scripts/grasp-sweep.sh oracle|random` (one `graspmap grasp` per object and seed).")
    rows = []
    for policy in ("oracle", "random"):
        try:
            last = [l for l in open(f"{d}/{policy}.log") if "succeeded" in l][-1]
            ok, total = re.search(r"(\d+)/(\d+) succeeded", last).groups()
            rows.append([policy, f"{ok}/{total}", f"{100 * int(ok) / int(total):.1f} %", f"{MACHINE}, {COMMIT}"])
        except (OSError, IndexError, AttributeError):
            rows.append([policy, DASH, DASH, f"{MACHINE}, {COMMIT}"])
    md(["policy", "successes", "rate", "machine, commit"], rows)


def t_collision():
    head("Collision check", "`graspmap eval ... --verify-top 0 --collision-check off|walls|full`.")
    rows = []
    for check, label in (("off", "`off` (the plain argmax)"), ("walls", "`walls`"), ("full", "`full` (default)")):
        tag = "vt0" if check == "full" else f"vt0-cc{check}"
        g = lambda s: ev(f"model-{s}-{tag}")
        rows.append([label, count(g("train")), rate(g("test")), moved(g("e"), span=False, lost=False),
                     moved(g("enp8"), span=False, lost=False)])
    md(["setting", "train, seed 0", f"test, {seeds(E['TEST_SEEDS'])}", f"empty_bin, {seeds(E['EMPTY_SEEDS'])}",
        f"empty_bin, {seeds(E['EMPTY_SEEDS'])}, np8"], rows)


def t_crop():
    d = f"{out}/crop"
    head("Crop training", f"`graspmap train --epochs {E['EPOCHS']} --crop 0|64` on a copy of the labels, then `eval`.")
    rows = []
    for crop in ("0", "64"):
        r = load(f"{d}/{crop}/train.json")
        g = lambda s: ev("eval-" + s, f"{d}/{crop}")
        rows.append([f"`--crop {crop}`", DASH if r is None else f"{r['wall_seconds']:.1f} s",
                     DASH if r is None else f"{r['best_val_loss']:.5f}", count(g("train")), rate(g("test")),
                     moved(g("enp8"))])
    md(["training", "wall", "best validation loss", "train, seed 0", f"test, {seeds(E['TEST_SEEDS'])}",
        f"empty_bin, {seeds(E['EMPTY_SEEDS'])}, np8"], rows)


def t_trials():
    d = f"{out}/trials"
    head("Learning from trials", f"`graspmap improve --rounds {E['ROUNDS']} --scenes {E['SCENES']} --epochs "
         f"{E['ROUND_EPOCHS']}` from the labelled model, then `eval --checkpoint` each model, with the default "
         "vetoes and as the plain argmax (`--verify-top 0 --collision-check off`).")
    rounds = load(f"{d}/improve.json") or []
    t = load(f"{d}/improve.time.json")
    print(f"The loop took {DASH if t is None else secs(t['wall_s'])}.")
    print()
    rows = []
    for i in range(int(E["ROUNDS"]) + 1):
        tag = "start" if i == 0 else f"round_{i:02d}"
        g = lambda s: ev(f"{tag}-{s}", f"{d}/eval")
        info = DASH if i == 0 or i > len(rounds) else (
            f"{rounds[i - 1]['trials']} trials, {pct(rounds[i - 1]['collection_success_rate'])} %")
        for argmax in ("", "-argmax"):
            rows.append([("labels only" if i == 0 else f"round {i}") + (" argmax" if argmax else ""), info,
                         count(g("train" + argmax)), rate(g("test" + argmax)), moved(g("enp8" + argmax)),
                         rate(g("enp8" + argmax)), rate(g("htest" + argmax)), moved(g("henp8" + argmax))])
        rows.append([("labels only" if i == 0 else f"round {i}") + ", `--give-up-after 6`", DASH, DASH, DASH,
                     moved(g("enp8-giveup6")), rate(g("enp8-giveup6")), DASH, moved(g("henp8-giveup6"))])
        rows.append([("labels only" if i == 0 else f"round {i}") + ", `--push-unverified false`", DASH, DASH, DASH,
                     moved(g("enp8-nopush")), rate(g("enp8-nopush")), DASH, moved(g("henp8-nopush"))])
        if i == int(E["ROUNDS"]):
            rows.append([f"round {i}, `--push-unverified false --verify-margin 6`", DASH, DASH, rate(g("test-before")),
                         moved(g("enp8-before")), rate(g("enp8-before")), rate(g("htest-before")),
                         moved(g("henp8-before"))])
    rows.append(["oracle (np8 in empty_bin)", DASH, count(ev("oracle-train")), rate(ev("oracle-test")),
                 moved(ev("oracle-enp8")), rate(ev("oracle-enp8")), rate(ev("oracle-htest")), moved(ev("oracle-henp8"))])
    rows.append(["oracle, np8, `--give-up-after 6`", DASH, DASH, DASH, moved(ev("oracle-enp8-giveup6")),
                 rate(ev("oracle-enp8-giveup6")), DASH, moved(ev("oracle-henp8-giveup6"))])
    md(["model", "collected", "train", f"test, {seeds(E['TEST_SEEDS'])}", f"empty_bin, {seeds(E['EMPTY_SEEDS'])}, np8",
        "its picks", f"held out: test, {seeds(E['HELD_TEST'])}", f"held out: empty_bin, {seeds(E['HELD_EMPTY'])}, np8"],
       rows)
    spread = []
    last = f"round_{int(E['ROUNDS']):02d}"
    for label, reports in (
            ("labels only", [ev(f"start-{s}", f"{d}/eval") for s in ("test", "htest", "spread")]),
            (f"round {E['ROUNDS']}", [ev(f"{last}-{s}", f"{d}/eval") for s in ("test", "htest")]
             + [ev("last-spread", f"{d}/eval")]),
            ("the oracle", [ev(f"oracle-{s}") for s in ("test", "htest", "spread")])):
        if any(r is None for r in reports):
            continue
        counts = [c for r in reports for c in per_seed(r)]
        per_seed_attempts = reports[0]["success"]["trials"] / len(reports[0]["seeds"])
        rates = [100 * sum(counts[i:i + 3]) / (3 * per_seed_attempts) for i in range(0, len(counts) - 2, 3)]
        overall = 100 * sum(counts) / (len(counts) * per_seed_attempts)
        spread.append(f"{label} {overall:.1f} % over all, sets " + ", ".join(f"{x:.1f}" for x in rates)
                      + f" (sd {statistics.stdev(rates):.1f})")
    if spread:
        print(f"Test on {seeds(E['TEST_SEEDS'])}, then {seeds(E['HELD_TEST'])}, then {seeds(E['SPREAD_SEEDS'])}, as "
              "consecutive sets of three seeds, in %: " + "; ".join(spread) + ".")
        print()


def t_slurm():
    d = f"{out}/slurm"
    head("Sweeps under Slurm", f"`eval --task empty_bin --policy oracle --seeds {E['SLURM_SEEDS']} --n-past-action 8` "
         "in one process (`--threads 2`), and as `SHARDS=2 CPUS_PER_TASK=1 scripts/slurm/submit.sh` on the one-node "
         "Slurm, from submission to the merge job's end.")
    single, slurm = load(f"{d}/single.time.json"), load(f"{d}/slurm.time.json")
    rows = []
    if single and slurm:
        overhead = slurm["wall_s"] - max(slurm["shard_walls"])
        rows.append([secs(single["wall_s"]), secs(slurm["wall_s"]), f"{slurm['wall_s'] / single['wall_s']:.2f}",
                     ", ".join(secs(w) for w in slurm["shard_walls"]), secs(overhead), slurm["state"]])
    md(["one process", "2 shards under Slurm", "ratio", "each shard's own eval time", "overhead (rest of the wall)",
        "merge job"], rows)


def t_verification():
    head("Verification", "`graspmap eval` with the defaults, `--verify-rejected 0`, `--verify-floor 0.25`, `--verify-square 0`, "
         "`--verify-strips 2 --verify-square 0` (the planner's rule), `--verify-top 0`.")
    rows, notes = [], []
    base = lambda s: ev(f"model-{s}")
    for tag, label in (("", "defaults"), ("vr0", "`--verify-rejected 0`"), ("vf25", "`--verify-floor 0.25`"),
                       ("sq0", "`--verify-square 0`"), ("planner", "`--verify-strips 2 --verify-square 0`"),
                       ("vt0", "`--verify-top 0`")):
        g = lambda s: ev(f"model-{s}-{tag}") if tag else base(s)
        rows.append([label, count(g("train")), rate(g("test")), moved(g("enp8"), span=False, lost=False),
                     moved(g("henp8"), span=False, lost=False)])
        if tag:
            notes.append(f"{label}: test {paired(g('test'), base('test'))}, empty_bin {paired(g('enp8'), base('enp8'))} "
                         f"and {paired(g('henp8'), base('henp8'))}")
    md(["setting", "train, seed 0", f"test, {seeds(E['TEST_SEEDS'])}", f"empty_bin, {seeds(E['EMPTY_SEEDS'])}, np8",
        f"empty_bin, {seeds(E['HELD_EMPTY'])}, np8"], rows)
    print("Paired per seed against the defaults: " + "; ".join(notes) + ".")
    print()


def t_centring():
    head("Centring", "`graspmap eval ... --verify-top 0 [--centring]`.")
    rows = []
    for tag, label in (("vt0", "`--verify-top 0`"), ("vt0-centring", "`--verify-top 0 --centring`")):
        g = lambda s: ev(f"model-{s}-{tag}")
        rows.append([label, count(g("train")), rate(g("test")), moved(g("enp8"), span=False, lost=False)])
    md(["setting", "train, seed 0", f"test, {seeds(E['TEST_SEEDS'])}", f"empty_bin, {seeds(E['EMPTY_SEEDS'])}, np8"],
       rows)


def t_suppression():
    head("Failure suppression", "`graspmap eval --task empty_bin --n-past-action 8` with one parameter changed.")
    base = ev("model-enp8")
    rows = [["defaults", moved(base, span=False, lost=False), DASH]]
    for tag, label in (("reach1", "`--suppress-rotation-reach 1`"), ("reach4", "`--suppress-rotation-reach 4`"),
                       ("sigma6", "`--suppression-sigma 6`"), ("successes", "`--suppress-successes`")):
        r = ev(f"model-enp8-{tag}")
        rows.append([label, moved(r, span=False, lost=False), paired(r, base)])
    off = ev("model-e")
    rows.append(["`--n-past-action 0` (off)", moved(off, span=False, lost=False), paired(off, base)])
    md(["setting", f"empty_bin, {seeds(E['EMPTY_SEEDS'])}", "paired against the defaults"], rows)


def t_variants():
    d = f"{out}/variants"
    head("Input and label variants", "`scripts/variants.sh`, then the floor and the held-out seeds per variant.")
    try:
        specs = [row.split("|") for row in open(f"{d}/rows.txt").read().strip().split(";") if row]
    except OSError:
        specs = []
    rows, notes, base = [], [], None
    for name, label, floor in specs:
        e = f"{d}/{name}/eval"
        if floor == "0":
            get = {"train": ev("train_vt200", e), "test": ev("test_vt200", e), "enp8": ev("empty_np8_vt200", e),
                   "htest": ev("htest", e), "henp8": ev("henp8", e)}
            lab, tr = load(f"{d}/{name}/label.json"), load(f"{d}/{name}/train.json")
            first = [f"{lab['total_labels']} ({lab['total_rounds']})" if lab else DASH,
                     f"{tr['wall_seconds']:.0f}" if tr else DASH, f"{tr['best_val_loss']:.5f}" if tr else DASH]
            base = base or get
        else:
            get = {s: ev(f"{s}-vf25", e) for s in ("train", "test", "enp8", "htest", "henp8")}
            first = ["(the same model)", "", ""]
        rows.append([label] + first + [count(get["train"]), rate(get["test"]),
                                       moved(get["enp8"], span=False, lost=False), rate(get["htest"]),
                                       moved(get["henp8"], span=False, lost=False)])
        if base is not get:
            notes.append(f"{label} {paired(get['test'], base['test'])}, {paired(get['enp8'], base['enp8'])}")
    short = lambda text: text.replace("-", "–").replace(",", "/")
    md(["variant", "labels (rounds)", "train s", "best val loss", "train, seed 0", f"test, {short(E['TEST_SEEDS'])}",
        f"empty_bin np8, {short(E['EMPTY_SEEDS'])}", f"test, {short(E['HELD_TEST'])}",
        f"empty_bin np8, {short(E['HELD_EMPTY'])}"], rows)
    print("Paired per seed against the default (test successes, empty_bin objects moved): "
          + ("; ".join(notes) or DASH) + ".")
    print()


def t_labelling():
    d = f"{out}/labelling"
    head("Labelling", f"`graspmap --data D [--threads 1] label --per-object {E['PER_OBJECT']}` from an empty data dir.")
    one, default = load(f"{d}/one.json"), load(f"{d}/default.json")
    try:
        rerun = "byte-identical" if open(f"{d}/rerun.txt").read().strip() == "identical" else "different (see diff.txt)"
    except OSError:
        rerun = DASH
    md(["machine", "commit", "labels (rounds)", "wall, `--threads 1`", "wall, default `--threads`", "rerun"],
       [[MACHINE, COMMIT, f"{one['total_labels']} ({one['total_rounds']})" if one else DASH,
         secs(one["wall_seconds"]) if one else DASH, secs(default["wall_seconds"]) if default else DASH, rerun]])


def t_soak():
    d = f"{out}/soak"
    head("Physics soak", "`GRASPMAP=... DATA=... scripts/soak.sh N M 4242`.")
    cols = {}
    for policy in ("random", "model"):
        scenes = attempts = no_reason = nonfinite = sunk = 0
        for path in sorted(glob.glob(f"{d}/reports/{policy}-*.json")):
            r = load(path) or {}
            for run in r.get("runs", []):
                scenes += 1
                for a in run["attempts"]:
                    attempts += 1
                    no_reason += not a.get("reason")
                    v = a.get("violations", [])
                    nonfinite += any("non-finite" in x for x in v)
                    sunk += any("inside the ground or a tote" in x for x in v)
        panics = sum(open(p).read().count("panicked") for p in glob.glob(f"{d}/reports/{policy}-*.err"))
        cols[policy] = (scenes, [panics, no_reason, nonfinite, f"{sunk} of {attempts:,}"])
    md(["check", f"random policy, {cols['random'][0]} scenes", f"model, {cols['model'][0]} scenes"],
       [[check, cols["random"][1][i], cols["model"][1][i]] for i, check in enumerate(
           ["panics", "attempts without a reason", "a NaN or infinite pose or velocity",
            "attempts with an object more than 5 mm inside the ground or a tote"])])
    print(f"Wall: {secs(wall(f'{d}/times.json'))}.")
    print()


def t_faults():
    d = f"{out}/faults"
    head("Faults", "`scripts/fuzz.sh SCALE` and `scripts/kill-resume.sh K 7`.")
    try:
        fuzz = open(f"{d}/fuzz.log").read()
    except OSError:
        fuzz = ""
    found = re.findall(r"^(fuzz_\w+): (\d+) cases each, no panic, no case over 5 s, under 2 GiB \((\d+) s\)", fuzz, re.M)
    json_rows = [f for f in found if f[0] == "fuzz_json_"]
    binary = [f for f in found if f[0] != "fuzz_json_"]
    rows = []
    if json_rows:
        rows.append(["fuzzing labels.json, clicks, split.json, progress.json, checkpoint state", "`scripts/fuzz.sh`",
                     f"{int(json_rows[0][1]):,} each", f"0 panics, every input under 5 s and 2 GiB ({json_rows[0][2]} s)"])
    if binary:
        rows.append(["fuzzing " + ", ".join(f[0][len("fuzz_"):] for f in binary), "`scripts/fuzz.sh`",
                     f"{int(binary[0][1]):,} each",
                     f"0 panics, every input under 5 s and 2 GiB ({sum(int(f[2]) for f in binary)} s)"])
    if len(found) < 7:
        rows.append(["fuzzing", "`scripts/fuzz.sh`", DASH, f"{7 - len(found)} of 7 passes failed (see fuzz.err)"])
    try:
        kills = open(f"{d}/kill.log").read().splitlines()
    except OSError:
        kills = []
    for what in ("label", "train"):
        lines = [l for l in kills if l.startswith(what + ": killed at ")]
        delays = [float(re.search(r"killed at ([\d.]+) s", l).group(1)) for l in lines]
        resumed = sum("--resume" in l for l in lines)
        span = f"{len(lines)} kills at {min(delays)}–{max(delays)} s" if delays else DASH
        note = f" ({resumed} with `--resume`)" if what == "train" else ""
        rows.append([f"SIGKILL during `{what}`", "`scripts/kill-resume.sh`", span,
                     f"{len(lines)} resumed byte-identical{note}" + ("" if kills and "every one" in kills[-1] else
                                                                      "; the run failed (see kill.err)")])
    md(["check", "command", "cases", "result"], rows)
    print(f"The fuzz pass took {secs(wall(f'{d}/fuzz.time.json'))}.")
    print()


def t_tests():
    d = f"{out}/tests"
    head("Test suite and build", "`./test.sh` and `scripts/install-check.sh` (= `bash .ci/run`) in a fresh clone.")
    try:
        text = open(f"{d}/test.log").read()
    except OSError:
        text = ""
    built = re.search(r"Finished `release` profile .*? in (.+)", text)
    unit = suite = other = 0
    suite_time, target = None, ""
    for line in text.splitlines():
        m = re.match(r"\s*(Running|Doc-tests) (\S+)", line)
        if m:
            target = m.group(2)
        m = re.match(r"test result: \w+\. (\d+) passed.*finished in ([\d.]+)s", line)
        if m:
            n = int(m.group(1))
            if "tests/suite" in target:
                suite, suite_time = suite + n, float(m.group(2))
            elif target.startswith("unittests"):
                unit += n
            else:
                other += n
    total = wall(f"{d}/test.time.json")
    install = wall(f"{d}/install.time.json")
    ci = None if total is None or install is None else total + install
    build = load(f"{d}/build.time.json")
    rows = [["`bash .ci/run` (`./test.sh`, then `scripts/install-check.sh`)", secs(ci), COMMIT],
            ["… building the test binaries", built.group(1).strip() if built else DASH, COMMIT],
            ["… tests", f"{unit + suite + other} passed: {unit} unit, {suite} in the suite"
             + (f" ({suite_time:.1f} s)" if suite_time is not None else ""), COMMIT],
            ["`scripts/install-check.sh` after `./test.sh`", secs(install), COMMIT],
            ["clean `cargo build --release --locked` (`git archive`, empty target dir)",
             f"{build['wall_s']:.1f} s wall, {build['user_s']:.1f} s user CPU" if build else "not run", COMMIT]]
    md(["measure", "figure", "commit"], rows)


def t_webpage():
    head("Labelling page", "The browser test through `./test.sh`; `target/browser/label-timings.json`.")
    t = load(f"{out}/webpage/label-timings.json")
    if t is None:
        md(["measure", "figure"], [["the browser test", "failed or did not run (see test.log)"]])
        return
    times = [r["confirm_to_outcome_s"] for r in t["rounds"]]
    ok = sum(r["reason"] == "success" for r in t["rounds"])
    md(["measure", "figure"], [
        ["first load (navigation start to `load`)", f"{t['first_load_ms']:.0f} ms"],
        [f"confirm (`Enter`) to the outcome on the page, median of {len(times)} rounds",
         f"{statistics.median(times):.2f} s" if times else DASH],
        [f"confirm to the outcome, slowest of {len(times)} rounds", f"{t['slowest_confirm_to_outcome_s']:.2f} s"],
        [f"the whole dataset, {len(times)} rounds, {ok} successes", f"{t['wall_s']:.1f} s"]])


def t_video():
    d = f"{out}/video"
    head("Videos and the report", "`graspmap --data D eval --task empty_bin --seeds 1 [--record ep.gif|ep.mp4]` "
         "with `GRASPMAP_LOG=debug`, then `graspmap report`.")
    rows = []
    for kind, label in (("none", "no `--record`"), ("gif", "`.gif`"), ("mp4", "`.mp4` (H.264)")):
        t = load(f"{d}/{kind}.time.json")
        size = frames = encoding = DASH
        if kind != "none" and os.path.exists(f"{d}/ep.{kind}"):
            n = os.path.getsize(f"{d}/ep.{kind}")
            size = f"{n:,} B ({n / 2 ** 20:.2f} MiB)"
            probe = load(f"{d}/{kind}.probe.json") or {}
            streams = probe.get("streams") or [{}]
            if streams[0].get("nb_read_frames"):
                frames = f"{streams[0]['nb_read_frames']}, {float(streams[0].get('duration') or 0):.1f} s"
            try:
                m = re.search(r"frames encoded and written in ([\d.]+) s", open(f"{d}/{kind}.log").read())
                encoding = f"{m.group(1)} s" if m else DASH
            except OSError:
                pass
        rows.append([label, size, frames, secs(t and t["wall_s"]), secs(t and t["user_s"]), encoding])
    md(["run", "size", "frames (ffprobe)", "wall", "user CPU", "encoding"], rows)
    report = load(f"{d}/report.json")
    files = len(report.get("files", [])) if report else 0
    print(f"`graspmap report`: {secs(wall(f'{d}/report.time.json'))}, the page and {files} files.")
    print()


globals()["t_" + table]()
PY
  cat "$out/$1.md"
}

# ---------------------------------------------------------------------------------------------
failed=()
for t in "${selected[@]}"; do
  log "== $t: $(describe "$t")"
  set +e
  (
    set -e
    "t_$t"
  )
  status=$?
  set -e
  if [[ $status -ne 0 ]]; then
    log "$t: a command failed (status $status); its logs are in $out"
    failed+=("$t")
  fi
  render "$t" || failed+=("$t (render)")
done
log "raw outputs and the tables (*.md) are in $out; machine and commit in $out/machine.txt"
if [[ ${#failed[@]} -gt 0 ]]; then
  log "failed: ${failed[*]}"
  exit 1
fi
