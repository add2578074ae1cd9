#!/usr/bin/env bash
# Installs the Debian packages the test suite runs, given as arguments (e.g. `ffmpeg`), when any
# is missing: ffprobe (from ffmpeg) checks the episode videos; chromium and chromium-driver run
# the browser test. Idempotent: when every package is
# installed it does nothing and prints nothing. Without root (or apt-get) it installs nothing and
# says which command would, and the tests that need the tool then fail naming it.
#
# Usage: scripts/setup-system.sh PACKAGE...
set -euo pipefail

missing=()
for package in "$@"; do
  if ! dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q 'install ok installed'; then
    missing+=("$package")
  fi
done
[ ${#missing[@]} -eq 0 ] && exit 0

if [ "$(id -u)" -ne 0 ] || ! command -v apt-get >/dev/null; then
  echo "setup-system: missing ${missing[*]}; install with: sudo apt-get install -y ${missing[*]}" >&2
  exit 0
fi
echo "setup-system: installing ${missing[*]}" >&2
export DEBIAN_FRONTEND=noninteractive
# A fresh image has no package lists; update only when the install cannot find the packages.
apt-get install -y --no-install-recommends "${missing[@]}" >/dev/null 2>&1 \
  || { apt-get update -qq && apt-get install -y --no-install-recommends "${missing[@]}" >/dev/null; }
