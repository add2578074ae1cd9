#!/usr/bin/env bash
# Installs the Python peer for `graspmap bench train`: the full torch==2.13.0 from PyPI (its
# CUDA wheels included, about 4.7 GB) into the git-ignored .venv-bench/, so that Python's
# `import torch` works. The product itself only needs the minimal .venv/ (setup-libtorch.sh).
# Idempotent: once installed, a rerun only compares a stamp file and prints nothing.
set -euo pipefail
cd "$(dirname "$0")/.."
venv=.venv-bench
stamp="$venv/torch.stamp"
want="torch==2.13.0"
if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$want" ]; then
  exit 0
fi
start=$SECONDS
python=${PYTHON:-python3}
if [ -d "$venv" ] && ! "$venv/bin/python" -c '' 2>/dev/null; then
  rm -rf "$venv"
fi
[ -d "$venv" ] || "$python" -m venv "$venv"
rm -f "$stamp"
"$venv/bin/python" -m pip install --quiet --progress-bar off --no-input "$want" >&2
"$venv/bin/python" -c 'import torch; assert torch.__version__.startswith("2.13.0"), torch.__version__'
echo "$want" >"$stamp"
echo "setup-bench-peer: installed $want into $venv ($((SECONDS - start)) s)" >&2
