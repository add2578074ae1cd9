#!/usr/bin/env bash
# Submits a graspmap sweep to Slurm as a job array, one task per shard, and a merge job that
# runs when every task has succeeded (docs/cluster.md).
#
# Usage: scripts/slurm/submit.sh eval ARGS...      e.g. eval --task empty_bin --seeds 1-100 --n-past-action 8
#        scripts/slurm/submit.sh collect ARGS...   e.g. collect --scenes 1000
#
# Every knob is an environment variable (defaults in brackets):
#   RUN_DIR        where the shards' outputs, logs and the merged result go; on shared storage [required]
#   SHARDS         array tasks, one shard each [4]
#   DATA           graspmap's data folder (model, labels), on shared storage [data]
#   GRASPMAP       the graspmap binary, on shared storage [target/release/graspmap of this checkout]
#   PARTITION      the partition [the cluster's default]
#   TIME_LIMIT     each task's time limit [01:00:00]
#   CPUS_PER_TASK  cores per shard, also its --threads [2]
#   MEM_PER_TASK   memory per shard [4G]
#   SETUP_PER_NODE 1: run scripts/setup-libtorch.sh in each task first, when libtorch is not on
#                  shared storage (GRASPMAP_CACHE_DIR) [0]
#   SBATCH_EXTRA   more sbatch flags, e.g. "--account=lab --qos=short" []
# It prints the array and merge job ids and keeps them, with the command, in RUN_DIR/jobs.env
# for scripts/slurm/resubmit.sh.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
repo="$(cd "$here/../.." && pwd)"
command="${1:-}"
case "$command" in
  eval | collect) shift ;;
  *)
    echo "submit.sh: the first argument is the command to shard, eval or collect (got '${command}')" >&2
    exit 2
    ;;
esac
: "${RUN_DIR:?set RUN_DIR to a folder on shared storage for the shards and the merged result}"
export RUN_DIR
export SHARDS="${SHARDS:-4}"
export DATA="${DATA:-data}"
export GRASPMAP="${GRASPMAP:-$repo/target/release/graspmap}"
export SETUP_PER_NODE="${SETUP_PER_NODE:-0}"
export GRASPMAP_REPO="$repo"
if ! [[ "$SHARDS" =~ ^[1-9][0-9]*$ ]]; then
  echo "submit.sh: SHARDS=$SHARDS is not a positive whole number" >&2
  exit 2
fi
if [ ! -x "$GRASPMAP" ]; then
  echo "submit.sh: GRASPMAP=$GRASPMAP is not an executable; build it (cargo build --release) or point GRASPMAP at one" >&2
  exit 2
fi
mkdir -p "$RUN_DIR/logs"
RUN_DIR="$(cd "$RUN_DIR" && pwd)"
DATA="$(mkdir -p "$DATA" && cd "$DATA" && pwd)"

# The command and its arguments, one per line, for resubmit.sh.
printf '%s\n' "$command" "$@" >"$RUN_DIR/command.args"

# shellcheck source=scripts/slurm/common.sh
source "$here/common.sh"
submit_shards "1-$SHARDS" "$command" "$@"
echo "array $array (${SHARDS} shards), merge $merge -> $RUN_DIR"
