#!/usr/bin/env bash
# A real one-node Slurm on this machine: munged, slurmctld and slurmd from slurm.conf.in, for
# the test suite (tests/suite/slurm.rs) and for trying the job scripts before a real cluster.
#
# Usage: scripts/slurm/local-cluster.sh start STATE_DIR   # prints the SLURM_CONF to export
#        scripts/slurm/local-cluster.sh stop STATE_DIR
#
# Needs root and Debian's slurm-wlm and munge packages (scripts/setup-system.sh installs them:
# sudo scripts/setup-system.sh slurm-wlm munge). Without them it fails, saying so.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
action="${1:?usage: local-cluster.sh start|stop STATE_DIR}"
state="$(mkdir -p "${2:?usage: local-cluster.sh start|stop STATE_DIR}" && cd "$2" && pwd)"
conf="$state/slurm.conf"

stop() {
  for pidfile in "$state/slurmd.pid" "$state/slurmctld.pid" "$state/munged.pid"; do
    if [ -s "$pidfile" ]; then
      kill "$(cat "$pidfile")" 2>/dev/null || true
    fi
  done
  # Give the daemons a moment to exit, then make sure.
  for _ in $(seq 50); do
    alive=0
    for pidfile in "$state/slurmd.pid" "$state/slurmctld.pid" "$state/munged.pid"; do
      [ -s "$pidfile" ] && kill -0 "$(cat "$pidfile")" 2>/dev/null && alive=1
    done
    [ "$alive" = 0 ] && break
    sleep 0.1
  done
  for pidfile in "$state/slurmd.pid" "$state/slurmctld.pid" "$state/munged.pid"; do
    [ -s "$pidfile" ] && kill -9 "$(cat "$pidfile")" 2>/dev/null || true
    rm -f "$pidfile"
  done
}

case "$action" in
  stop)
    stop
    exit 0
    ;;
  start) ;;
  *)
    echo "local-cluster.sh: unknown action '$action' (start or stop)" >&2
    exit 2
    ;;
esac

missing=()
for tool in munged slurmctld slurmd sbatch; do
  command -v "$tool" >/dev/null || missing+=("$tool")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "local-cluster.sh: ${missing[*]} not found; install with: sudo scripts/setup-system.sh slurm-wlm munge" >&2
  exit 1
fi
if [ "$(id -u)" -ne 0 ]; then
  echo "local-cluster.sh: slurmd runs jobs as their users and needs root; run as root (sudo)" >&2
  exit 1
fi

stop
node="$(hostname -s)"
cpus="$(nproc)"
memory="$(awk '/MemTotal/ { print int($2 / 1024 * 0.9) }' /proc/meminfo)"
mkdir -p "$state/ctld" "$state/slurmd" "$state/munge"
sed -e "s|@STATE@|$state|g" -e "s|@NODE@|$node|g" -e "s|@CPUS@|$cpus|g" \
  -e "s|@MEMORY@|$memory|g" "$here/slurm.conf.in" >"$conf"

# munged: its own socket and key copy in the state folder, so a system munged is left alone.
install -m 0400 -o munge -g munge /etc/munge/munge.key "$state/munge/munge.key" 2>/dev/null \
  || { echo "local-cluster.sh: /etc/munge/munge.key missing; reinstall munge (apt-get install --reinstall munge)" >&2; exit 1; }
chown munge:munge "$state/munge"
chmod 0700 "$state/munge"
socket="$state/munge/munge.socket"
munged --force --key-file "$state/munge/munge.key" --socket "$socket" \
  --pid-file "$state/munged.pid" --log-file "$state/munge/munged.log" --seed-file "$state/munge/seed"
# Slurm finds munged's socket through its own setting.
echo "AuthInfo=socket=$socket" >>"$conf"

export SLURM_CONF="$conf"
slurmctld -f "$conf"
slurmd -f "$conf" -N "$node"
for _ in $(seq 100); do
  if sinfo -h -o '%T' 2>/dev/null | grep -qE '^(idle|mixed|allocated)'; then
    echo "$conf"
    exit 0
  fi
  sleep 0.2
done
echo "local-cluster.sh: the node did not come up; see $state/slurmctld.log and $state/slurmd.log" >&2
sinfo >&2 || true
exit 1
