#!/usr/bin/env bash
# Resubmits failed (or cancelled) array tasks of a sweep alone, and a new merge job that runs
# when they succeed; the shards that finished are kept (docs/cluster.md).
#
# Usage: RUN_DIR=... scripts/slurm/resubmit.sh TASK[,TASK...]   e.g. 3 or 2,5
# The same knobs as submit.sh apply (TIME_LIMIT, PARTITION, ...); the command comes from
# RUN_DIR/command.args and the shard count from RUN_DIR/jobs.env.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
repo="$(cd "$here/../.." && pwd)"
tasks="${1:?usage: RUN_DIR=... resubmit.sh TASK[,TASK...]}"
: "${RUN_DIR:?set RUN_DIR to the folder of the sweep, where jobs.env is}"
RUN_DIR="$(cd "$RUN_DIR" && pwd)"
export RUN_DIR
# shellcheck source=/dev/null
source "$RUN_DIR/jobs.env"
export SHARDS
export DATA="${DATA:-data}"
DATA="$(cd "$DATA" && pwd)"
export GRASPMAP="${GRASPMAP:-$repo/target/release/graspmap}"
export SETUP_PER_NODE="${SETUP_PER_NODE:-0}"
export GRASPMAP_REPO="$repo"
mapfile -t args <"$RUN_DIR/command.args"
command="${args[0]}"

# The old merge waits on tasks that failed: it never runs; make sure it is gone.
scancel "$MERGE_JOB" 2>/dev/null || true

# shellcheck source=scripts/slurm/common.sh
source "$here/common.sh"
submit_shards "$tasks" "${args[@]}"
echo "resubmitted tasks $tasks as array $array, merge $merge -> $RUN_DIR"
