#!/usr/bin/env bash
# Reruns the tables of BENCHMARKS.md on this machine and prints each as Markdown, in the columns
# BENCHMARKS.md uses. Every table calls the existing tools, each writing JSON: the release binary
# with --json, `graspmap bench train`, `cargo bench` (criterion), scripts/soak.sh,
# scripts/variants.sh, scripts/grasp-sweep.sh, scripts/fuzz.sh, scripts/kill-resume.sh and
# ./test.sh; scripts/benchmarks/render.py then renders each table from those JSON files alone, and
# a file that should be there and is not fails the table with its name.
#
# Usage: scripts/benchmarks.sh [--quick] [TABLE...]    (no TABLE: every table, in --list order)
#        scripts/benchmarks.sh --list
#   --quick   a smoke run with tiny settings: 2 labels per object, 1 epoch, one seed per task
#             (two in empty_bin, one for each shard of the threads table), --max-attempts 2,
#             2 timed bench steps, 1 s per frame micro-benchmark, a 2 + 1 scene soak, 1 % of the
#             fuzz cases, 1 kill each; its figures only show that every table runs
#   OUT=DIR   where the raw outputs go (default target/benchmarks); each table also writes
#             OUT/TABLE.md, OUT/machine.txt records lscpu's model name and flags and the commit,
#             and OUT/settings.json the same with the run's counts and seeds for the renderer.
#             Evaluations are named for what they run: OUT/eval/model-empty_bin-heldout-np8.json,
#             OUT/eval/model-test+verify-top-0+collision-check-off.json
#   GRASPMAP=path/to/graspmap   use that binary instead of building target/release/graspmap
#   MODEL=DIR  take the labels and best.* of DIR (e.g. data, as ./demo.sh leaves it) as the model
#             of the tables that need one, instead of labelling and training one into OUT/model
#   BF16=1    also run bf16 training and bench on a CPU without native bf16 (libtorch emulates it)
#   PEER=1    with --quick, still time the Python peer of `bench train` (full runs always do; the
#             first use installs torch into .venv-bench/, about 4.7 GB)
#   MESH_OBJECTS=DIR  the placing table's second column: an objects dir (with split.json) of meshes
#
# `python3 scripts/benchmarks/render.py TABLE OUT` prints a table again from OUT's JSON.
# Outcomes (labels, weights, grasps, success rates) are deterministic per machine; times are not.
# A full run takes hours on 2 cores (the variants alone about 40 minutes, the soak about 25).
set -euo pipefail
self=$(realpath "$0")
cd "$(dirname "$self")/.."
root=$(pwd)

# The tables in --list order, each with a line on what it runs.
mapfile -t listing <scripts/benchmarks/tables.txt
tables=("${listing[@]%%$'\t'*}")
describe() { for line in "${listing[@]}"; do [[ ${line%%$'\t'*} != "$1" ]] || echo "${line#*$'\t'}"; done; }

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
  EPOCHS=1 PER_OBJECT=2 TEST_SEEDS=0 HELD_TEST=3000 EMPTY_SEEDS=1-2 HELD_EMPTY=11 MAX_ATTEMPTS=2
  ROUNDS=1 SCENES=2 ROUND_EPOCHS=1 SLURM_SEEDS=1-2 SPREAD_SEEDS='' OBJECT_SEEDS=1
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
  SPREAD_SEEDS MESH_OBJECTS=${MESH_OBJECTS:-}
helper() { python3 "$root/scripts/benchmarks/helpers.py" "$@"; }

out=$(realpath -m "${OUT:-target/benchmarks}")
mkdir -p "$out/eval" "$out/logs"
# Evaluations are shared between tables (quality, yardstick, verification, ... reuse the same runs)
# within one invocation, never across invocations: a report counts only when its .run file holds
# this run's id.
run_id="$(date +%s)-$$"

# The machine (lscpu's model and flags), the commit and the run's settings: OUT/machine.txt for
# people, OUT/settings.json for render.py; prints 1 when the CPU has native bf16.
native_bf16=$(helper settings "$out" "$quick" OBJECT_SEEDS EPOCHS PER_OBJECT TEST_SEEDS HELD_TEST EMPTY_SEEDS \
  HELD_EMPTY MAX_ATTEMPTS ROUNDS SCENES ROUND_EPOCHS SLURM_SEEDS SPREAD_SEEDS MESH_OBJECTS)

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
timed() { helper timed "$@"; }

# eval_name BASE [FLAGS...]: the file name of an evaluation, its flags spelt out after BASE:
# `eval_name model-test --verify-top 0 --centring` is model-test+verify-top-0+centring.
eval_name() { helper eval-name "$@"; }

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

# spec_args SPEC: the task, seeds and memory each evaluation name stands for, into `spec`.
spec_args() {
  local at=(--max-attempts "$MAX_ATTEMPTS") np8=(--n-past-action 8)
  case $1 in
    train-seed0) spec=(--task train --seeds 0) ;;
    train-seeds1-3) spec=(--task train --seeds 1-3) ;;
    test) spec=(--task test --seeds "$TEST_SEEDS") ;;
    test-heldout) spec=(--task test --seeds "$HELD_TEST") ;;
    test-spread) spec=(--task test --seeds "$SPREAD_SEEDS") ;;
    empty_bin-seed2-np8) spec=(--task empty_bin --seeds 2 "${np8[@]}" "${at[@]}") ;;
    empty_bin) spec=(--task empty_bin --seeds "$EMPTY_SEEDS" "${at[@]}") ;;
    empty_bin-np8) spec=(--task empty_bin --seeds "$EMPTY_SEEDS" "${np8[@]}" "${at[@]}") ;;
    empty_bin-np25) spec=(--task empty_bin --seeds "$EMPTY_SEEDS" --n-past-action 25 "${at[@]}") ;;
    empty_bin-heldout) spec=(--task empty_bin --seeds "$HELD_EMPTY" "${at[@]}") ;;
    empty_bin-heldout-np8) spec=(--task empty_bin --seeds "$HELD_EMPTY" "${np8[@]}" "${at[@]}") ;;
    *) die "no evaluation spec $1" ;;
  esac
}

# ev POLICY SPEC [FLAGS...]: the model dir's evaluation into OUT/eval/POLICY-SPEC[+FLAG...].json.
ev() {
  local policy=$1 name=$1-$2 spec
  spec_args "$2"
  shift 2
  ensure_model
  eval_into "$out/eval/$(eval_name "$name" "$@").json" "$model_dir" --policy "$policy" "${spec[@]}" "$@"
}

# evals POLICY "SPEC..." [FLAGS...]: ev for each SPEC.
evals() {
  local policy=$1 specs=$2 spec
  shift 2
  for spec in $specs; do ev "$policy" "$spec" "$@"; done
}

# ev_in DIR DATA PREFIX SPEC [FLAGS...]: an evaluation of DATA into DIR/PREFIXSPEC[+FLAG...].json,
# with the array `with` (a --checkpoint, say) passed on but left out of the name.
with=()
ev_in() {
  local dir=$1 data=$2 name=$3$4 spec
  spec_args "$4"
  shift 4
  eval_into "$dir/$(eval_name "$name" "$@").json" "$data" "${with[@]}" "${spec[@]}" "$@"
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

# Labels for the training tables: the model's when it was labelled in this run, else label anew.
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

# bf16_applies DIR: whether bf16 runs here; if not, DIR/bf16.skipped.json says why.
bf16_applies() {
  [[ $native_bf16 == 1 || ${BF16:-0} == 1 ]] && return 0
  helper skip "$1/bf16.skipped.json" "no native bf16 on this CPU (BF16=1 runs it emulated)"
  return 1
}

# ---------------------------------------------------------------------------------------------
# The tables: each runs its commands into OUT; scripts/benchmarks/render.py reads what they leave.

# pipeline_step NAME ARGS...: one timed graspmap command of the pipeline table.
pipeline_step() {
  local d=$out/pipeline name=$1
  shift
  timed "$d/times/$name.json" "$bin" --data "$d/data" --quiet --json "$d/$name.json" "$@" >"$d/$name.log" 2>&1
}

t_pipeline() {
  local d=$out/pipeline start=$SECONDS
  rm -rf "$d"
  mkdir -p "$d/times"
  log "pipeline: ./demo.sh's steps into $d/data"
  pipeline_step label label --per-object "$PER_OBJECT"
  pipeline_step train train --epochs "$EPOCHS"
  pipeline_step eval_train eval --task train
  pipeline_step eval_test eval --task test
  pipeline_step eval_empty_bin eval --task empty_bin --n-past-action 8 --max-attempts "$MAX_ATTEMPTS" \
    --record "$d/empty_bin.mp4"
  pipeline_step report report
  echo "{\"wall_s\": $((SECONDS - start))}" >"$d/times/total.json"
  echo "$run_id" >"$d/run"
}

t_training() {
  local d=$out/training precision
  rm -rf "$d"
  mkdir -p "$d"
  ensure_labels
  for precision in fp32 bf16; do
    [[ $precision == fp32 ]] || bf16_applies "$d" || continue
    mkdir -p "$d/$precision"
    cp -r "$labels_dir" "$d/$precision/labels"
    log "training: train --epochs $EPOCHS --precision $precision"
    "$bin" --data "$d/$precision" --quiet --json "$d/$precision/train.json" train --epochs "$EPOCHS" \
      --precision "$precision" >"$d/$precision/train.log" 2>&1
    helper epoch-seconds "$d/$precision/affordance/losses.csv" "$d/$precision/epoch-seconds.json"
  done
}

t_crop() {
  local d=$out/crop crop spec
  rm -rf "$d"
  ensure_labels
  for crop in 0 64; do
    mkdir -p "$d/$crop"
    cp -r "$labels_dir" "$d/$crop/labels"
    log "crop: train --epochs $EPOCHS --crop $crop"
    "$bin" --data "$d/$crop" --quiet --json "$d/$crop/train.json" train --epochs "$EPOCHS" \
      --crop "$crop" >"$d/$crop/train.log" 2>&1
    for spec in train-seed0 test empty_bin-np8; do ev_in "$d/$crop/eval" "$d/$crop" "" "$spec"; done
  done
}

# The loop from the default model (labels and crops), then every round's model and the start
# model on train, test and empty_bin (held-out seeds too), with the vetoes and as the plain
# argmax; the oracle with memory beside them, and the spread of test between seed sets.
t_trials() {
  local d=$out/trials spec tag last
  local argmax=(--verify-top 0 --collision-check off) before=(--push-unverified false --verify-margin 6)
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
    with=(--checkpoint "$d/data/improve/$tag/model/best.safetensors")
    [[ $tag != start ]] || with=(--checkpoint "$d/data/affordance/best.safetensors")
    for spec in train-seed0 test test-heldout empty_bin-np8 empty_bin-heldout-np8; do
      ev_in "$d/eval" "$d/data" "$tag-" "$spec"
      ev_in "$d/eval" "$d/data" "$tag-" "$spec" "${argmax[@]}"
    done
    for spec in empty_bin-np8 empty_bin-heldout-np8; do
      ev_in "$d/eval" "$d/data" "$tag-" "$spec" --give-up-after 6
      ev_in "$d/eval" "$d/data" "$tag-" "$spec" --push-unverified false
    done
  done
  # The last round with the checks as they were before pushing and the 3 mm squeeze margin.
  last=$(printf 'round_%02d' "$ROUNDS")
  with=(--checkpoint "$d/data/improve/$last/model/best.safetensors")
  for spec in test test-heldout empty_bin-np8 empty_bin-heldout-np8; do
    ev_in "$d/eval" "$d/data" "$last-" "$spec" "${before[@]}"
  done
  with=()
  evals oracle "train-seed0 test test-heldout empty_bin-np8 empty_bin-heldout-np8"
  evals oracle "empty_bin-np8 empty_bin-heldout-np8" --give-up-after 6
  # How far apart two sets of three test seeds fall on their own: test and held-out test of the
  # labels-only model, the last round and the oracle, with more seeds (SPREAD_SEEDS) beside them.
  [[ -n $SPREAD_SEEDS ]] || return 0
  with=(--checkpoint "$d/data/affordance/best.safetensors")
  ev_in "$d/eval" "$d/data" start- test-spread
  with=(--checkpoint "$d/data/improve/$last/model/best.safetensors")
  ev_in "$d/eval" "$d/data" last- test-spread
  with=()
  ev oracle test-spread
}

t_slurm() {
  local d=$out/slurm conf
  rm -rf "$d"
  mkdir -p "$d/data"
  conf=$(scripts/slurm/local-cluster.sh start "$d/cluster") || die "the one-node Slurm did not start (needs root, slurm-wlm and munge)"
  local sweep=(eval --task empty_bin --policy oracle --seeds "$SLURM_SEEDS" --n-past-action 8 --max-attempts "$MAX_ATTEMPTS")
  log "slurm: ${sweep[*]} in one process, then in 2 shards under Slurm"
  timed "$d/one-process.time.json" "$bin" --data "$d/data" --quiet --threads 2 --json "$d/one-process.json" \
    "${sweep[@]}" >"$d/one-process.log" 2>&1
  helper slurm "$d" "$conf" "$bin" "${sweep[@]}"
  scripts/slurm/local-cluster.sh stop "$d/cluster"
}

t_objects() {
  local d=$out/objects set dir task
  mkdir -p "$d"
  for set in bundled ycb-meshes; do
    dir=()
    [[ $set == bundled ]] || dir=(--objects-dir "$root/assets/ycb-meshes")
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
  cp -r "$model_dir" "$d/one-process"
  log "threads: ${sweep[*]} with --threads 2 in one process"
  timed "$d/one-process.time.json" "$bin" --data "$d/one-process" --quiet --threads 2 --json "$d/one-process.json" \
    "${sweep[@]}" >"$d/one-process.log" 2>&1
  log "threads: the same sweep as two 1-thread shard processes at once"
  cp -r "$model_dir" "$d/two-processes"
  helper shards "$d" "$bin" "${sweep[@]}"
}

t_pytorch() {
  local d=$out/bench precision peer=()
  mkdir -p "$d"
  rm -f "$d"/*.json
  if ((quick)) && [[ ${PEER:-0} != 1 ]]; then peer=(--no-peer); fi
  for precision in bf16 fp32; do
    [[ $precision == fp32 ]] || bf16_applies "$d" || continue
    log "pytorch: bench train --precision $precision"
    "$bin" --quiet --json "$d/$precision.json" bench train --precision "$precision" \
      --steps "$BENCH_STEPS" --rounds "$BENCH_ROUNDS" "${peer[@]}" >"$d/$precision.log" 2>&1
  done
}

t_latency() { evals model "empty_bin-np8 train-seed0 test"; }

# Criterion's results go to OUT/workcell/criterion; --quick gives it a second per benchmark.
t_workcell() {
  local d=$out/workcell times=()
  rm -rf "$d"
  mkdir -p "$d"
  ((quick)) && times=(--warm-up-time 1 --measurement-time 1)
  log "workcell: cargo bench --bench workcell"
  CRITERION_HOME=$d/criterion cargo bench --locked --bench workcell -- "${times[@]}" >"$d/bench.log" 2>"$d/bench.err"
  timed "$d/grasp.time.json" "$bin" --quiet grasp --object YcbPowerDrill --seed 2 --oracle >"$d/grasp.log" 2>&1
}

t_quality() {
  evals model "train-seed0 test empty_bin-seed2-np8 empty_bin empty_bin-np8 test-heldout empty_bin-heldout-np8"
  evals random "train-seed0 test empty_bin"
  evals oracle "train-seed0 test empty_bin empty_bin-np8 empty_bin-heldout-np8"
}

t_yardstick() {
  evals oracle "empty_bin empty_bin-np8 empty_bin-np25 empty_bin-heldout empty_bin-heldout-np8"
  evals model "empty_bin-np8 empty_bin-heldout-np8"
}

# VPG's cases: the model (with the default verification margin and with 10 mm) and the oracle on
# the scene files the tests carry, each scene file once per seed; spec_args does not apply (the
# task reads --scenes, not a drop seed).
t_scenes() {
  local seeds=0-4 name flags
  ((quick)) && seeds=0
  ensure_model
  for name in model model+verify-margin-10 oracle; do
    case $name in
      model) flags=(--policy model) ;;
      model+verify-margin-10) flags=(--policy model --verify-margin 10) ;;
      oracle) flags=(--policy oracle) ;;
    esac
    eval_into "$out/scenes/$name.json" "$model_dir" --objects-dir "$root/assets/blocks" "${flags[@]}" \
      --task scenes --scenes "$root/tests/fixtures/vpg" --seeds "$seeds" --n-past-action 8
  done
}

t_placing() {
  local policy
  for policy in model oracle; do
    evals "$policy" "empty_bin-np8 train-seeds1-3"
    [[ -z $MESH_OBJECTS ]] || evals "$policy" "empty_bin-np8 train-seeds1-3" --objects-dir "$(realpath "$MESH_OBJECTS")"
  done
}

t_sweep() {
  local d=$out/sweep policy
  mkdir -p "$d"
  for policy in oracle random; do
    log "sweep: scripts/grasp-sweep.sh $policy $SWEEP_SEEDS"
    # shellcheck disable=SC2086 # the seeds are separate arguments
    JSON=$d/$policy.json scripts/grasp-sweep.sh "$policy" $SWEEP_SEEDS >"$d/$policy.log" 2>"$d/$policy.err"
  done
}

t_collision() {
  local specs="train-seed0 test empty_bin empty_bin-np8"
  evals model "$specs" --verify-top 0
  evals model "$specs" --verify-top 0 --collision-check off
  evals model "$specs" --verify-top 0 --collision-check walls
}

t_verification() {
  local specs="train-seed0 test empty_bin-np8 empty_bin-heldout-np8"
  evals model "$specs"
  evals model "$specs" --verify-rejected 0
  evals model "$specs" --verify-floor 0.25
  evals model "$specs" --verify-square 0
  evals model "$specs" --verify-strips 2 --verify-square 0
  evals model "$specs" --verify-margin 6
  evals model "$specs" --push-unverified false
  evals model "$specs" --verify-top 0
}

t_centring() {
  evals model "train-seed0 test empty_bin-np8" --verify-top 0
  evals model "train-seed0 test empty_bin-np8" --verify-top 0 --centring
}

t_suppression() {
  evals model "empty_bin empty_bin-np8"
  local flags
  for flags in "--suppress-rotation-reach 1" "--suppress-rotation-reach 4" "--suppression-sigma 6" --suppress-successes; do
    # shellcheck disable=SC2086 # a setting's words are separate arguments
    ev model empty_bin-np8 $flags
  done
}

# The floor and the held-out seeds for the default and for rgbd with clutter 3 (the rows of
# BENCHMARKS.md); variants.sh writes the rest into DIR/eval/. OUT/variants/rows.json lists the
# rows, and which have held-out seeds.
t_variants() {
  local d=$out/variants v name input clutter per label shown rows=() first="" spec heldout
  log "variants: scripts/variants.sh with VARIANTS=\"$VARIANT_LIST\""
  GRASPMAP=$bin VARIANTS=$VARIANT_LIST EXTRA=0 EPOCHS=$EPOCHS TEST_SEEDS=$TEST_SEEDS \
    EMPTY_SEEDS=$EMPTY_SEEDS scripts/variants.sh "$d" >"$out/logs/variants.md" 2>"$out/logs/variants.err"
  for v in $VARIANT_LIST; do
    IFS=: read -r input clutter per <<<"$v"
    name="$input-c$clutter${per:+-p$per}"
    label="$input, clutter $clutter${per:+, $per per object}"
    shown=$label
    [[ -n $first ]] || { first=$name && shown+=" (default)"; }
    heldout=false
    if [[ $name == "$first" || ($input == rgbd && $clutter == 3 && (-z ${per:-} || $quick == 1)) ]]; then heldout=true; fi
    rows+=("{\"name\": \"$name\", \"label\": \"$shown\", \"floor\": false, \"heldout\": $heldout}")
    if [[ $heldout == true ]]; then
      ev_in "$d/$name/eval" "$d/$name" "" test-heldout
      ev_in "$d/$name/eval" "$d/$name" "" empty_bin-heldout-np8
      for spec in train-seed0 test empty_bin-np8 test-heldout empty_bin-heldout-np8; do
        ev_in "$d/$name/eval" "$d/$name" "" "$spec" --verify-floor 0.25
      done
      rows+=("{\"name\": \"$name\", \"label\": \"$label, floor 0.25\", \"floor\": true, \"heldout\": true}")
    fi
  done
  (IFS=,; echo "[${rows[*]}]") >"$d/rows.json"
}

t_labelling() {
  local d=$out/labelling
  rm -rf "$d"
  mkdir -p "$d"
  log "labelling: label with --threads 1, then with the default"
  "$bin" --data "$d/one-thread" --quiet --threads 1 --json "$d/one-thread.json" label --per-object "$PER_OBJECT" \
    >"$d/one-thread.log" 2>&1
  "$bin" --data "$d/default-threads" --quiet --json "$d/default-threads.json" label --per-object "$PER_OBJECT" \
    >"$d/default-threads.log" 2>&1
  local identical=true
  diff -r -x .lock "$d/one-thread/labels" "$d/default-threads/labels" >"$d/diff.txt" || identical=false
  echo "{\"identical\": $identical}" >"$d/rerun.json"
}

t_soak() {
  local d=$out/soak
  rm -rf "$d"
  mkdir -p "$d"
  ensure_model
  log "soak: scripts/soak.sh $SOAK_RANDOM $SOAK_MODEL 4242"
  GRASPMAP=$bin DATA=$model_dir JSON=$d/summary.json timed "$d/soak.time.json" scripts/soak.sh "$SOAK_RANDOM" \
    "$SOAK_MODEL" 4242 >"$d/soak.log" 2>"$d/soak.err" || true
}

t_faults() {
  local d=$out/faults
  rm -rf "$d"
  mkdir -p "$d"
  log "faults: scripts/fuzz.sh $FUZZ_SCALE"
  JSON=$d/fuzz.json timed "$d/fuzz.time.json" scripts/fuzz.sh "$FUZZ_SCALE" >"$d/fuzz.log" 2>"$d/fuzz.err" || true
  log "faults: scripts/kill-resume.sh $KILLS 7"
  JSON=$d/kill-resume.json timed "$d/kill.time.json" scripts/kill-resume.sh "$KILLS" 7 >"$d/kill.log" 2>"$d/kill.err" || true
}

t_tests() {
  local d=$out/tests tmp
  rm -rf "$d"
  mkdir -p "$d"
  if ((quick)); then
    # A smoke run: one test through ./test.sh in this checkout, no fresh clone, no clean build.
    log "tests: ./test.sh matmul_on_cpu (quick)"
    timed "$d/test.time.json" ./test.sh matmul_on_cpu >"$d/test.log" 2>&1
    helper cargo-test "$d/test.log" "$d/cargo-test.json"
    helper skip "$d/install.skipped.json" "--quick"
    helper skip "$d/build.skipped.json" "--quick"
    return 0
  fi
  tmp=$(mktemp -d)
  # shellcheck disable=SC2064 # the path is fixed now
  trap "rm -rf '$tmp'" EXIT
  git clone -q "$root" "$tmp/clone"
  log "tests: ./test.sh and scripts/install-check.sh (= .ci/run) in a fresh clone"
  (cd "$tmp/clone" && timed "$d/test.time.json" ./test.sh) >"$d/test.log" 2>&1
  helper cargo-test "$d/test.log" "$d/cargo-test.json"
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

# The eval report records the video's encoding time; ffprobe (when installed) the frames and size.
t_video() {
  local d=$out/video kind
  rm -rf "$d"
  mkdir -p "$d"
  ensure_model
  for kind in none gif mp4; do
    local record=()
    [[ $kind == none ]] || record=(--record "$d/ep.$kind")
    log "video: eval --task empty_bin --seeds 1 ${record[*]}"
    timed "$d/$kind.time.json" "$bin" --data "$model_dir" --quiet --json "$d/$kind.json" eval --task empty_bin \
      --seeds 1 --max-attempts "$MAX_ATTEMPTS" "${record[@]}" >"$d/$kind.log" 2>&1
    [[ $kind != none ]] || continue
    if command -v ffprobe >/dev/null; then
      ffprobe -v error -select_streams v:0 -count_frames -show_entries \
        stream=codec_name,nb_read_frames,duration:format=size -of json "$d/ep.$kind" >"$d/$kind.probe.json"
    else
      helper file-size "$d/ep.$kind" "$d/$kind.probe.json"
    fi
  done
  timed "$d/report.time.json" "$bin" --data "$model_dir" --quiet --json "$d/report.json" report \
    --out "$d/report.html" >"$d/report.log" 2>&1
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
  if python3 scripts/benchmarks/render.py "$t" "$out" >"$out/$t.md"; then
    cat "$out/$t.md"
  else
    failed+=("$t (render)")
  fi
done
log "raw outputs and the tables (*.md) are in $out; machine and commit in $out/machine.txt"
if [[ ${#failed[@]} -gt 0 ]]; then
  log "failed: ${failed[*]}"
  exit 1
fi
