#!/usr/bin/env bash
# One pick attempt per object and seed with a chosen policy, as BENCHMARKS.md reports them.
# usage: scripts/grasp-sweep.sh oracle|random [seeds...]   (default seeds: 1 2 3)
#   JSON=FILE  also write the counts to FILE: {"policy", "seeds", "successes", "attempts"}
set -euo pipefail
cd "$(dirname "$0")/.."
policy=${1:?usage: grasp-sweep.sh oracle|random [seeds...]}
shift
seeds=${*:-1 2 3}
cargo build --release --locked --quiet
bin=target/release/graspmap
# Every quoted name in the split file, train objects first.
objects=$(grep -o '"[^"]*"' assets/objects/split.json | tr -d '"' | grep -vx 'train\|test')
total=0
ok=0
for object in $objects; do
  for seed in $seeds; do
    line=$("$bin" grasp --object "$object" --seed "$seed" "--$policy")
    echo "$line"
    total=$((total + 1))
    case "$line" in *": success ["*) ok=$((ok + 1)) ;; esac
  done
done
echo "$policy: $ok/$total succeeded"
if [[ -n ${JSON:-} ]]; then
  printf '{"policy": "%s", "seeds": [%s], "successes": %d, "attempts": %d}\n' \
    "$policy" "$(echo "$seeds" | tr -s ' ' ',')" "$ok" "$total" >"$JSON"
fi
