# Sourced by submit.sh and resubmit.sh: submits array tasks and the merge job that waits for
# them, and records both in RUN_DIR/jobs.env. Needs here, RUN_DIR, SHARDS and the knobs of
# submit.sh in the environment.

# submit_shards TASKS COMMAND ARGS...: TASKS as sbatch --array takes them (1-4, or 2,5);
# sets array and merge to the new job ids.
submit_shards() {
  local tasks="$1" command="$2"
  shift 2
  local flags=(--parsable --time "${TIME_LIMIT:-01:00:00}" --cpus-per-task "${CPUS_PER_TASK:-2}"
    --mem "${MEM_PER_TASK:-4G}")
  [ -n "${PARTITION:-}" ] && flags+=(--partition "$PARTITION")
  # shellcheck disable=SC2206 # word splitting of the extra flags is the point
  [ -n "${SBATCH_EXTRA:-}" ] && flags+=($SBATCH_EXTRA)
  array=$(sbatch "${flags[@]}" --array="$tasks" --job-name "graspmap-$command" \
    --output "$RUN_DIR/logs/shard_%a.out" "$here/shard.sbatch" "$command" "$@")
  array="${array%%;*}"
  merge=$(sbatch "${flags[@]}" --dependency="afterok:$array" --kill-on-invalid-dep=yes \
    --job-name "graspmap-merge" --output "$RUN_DIR/logs/merge.out" "$here/merge.sbatch" "$command")
  merge="${merge%%;*}"
  cat >"$RUN_DIR/jobs.env" <<ENV
ARRAY_JOB=$array
MERGE_JOB=$merge
SHARDS=$SHARDS
ENV
}
