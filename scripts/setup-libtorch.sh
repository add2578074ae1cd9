#!/usr/bin/env bash
# Installs the libtorch that tch 0.26 needs (PyTorch 2.13.0) from PyPI into the project-local,
# git-ignored .venv/, and links it as .venv/libtorch, where .cargo/config.toml points LIBTORCH.
#
# Only what the Rust build and binaries load is installed, without pip's dependency resolution:
# the torch wheel (libtorch_cpu, libc10, libgomp, headers) and the two CUDA runtime libraries
# that libtorch_cpu.so names in DT_NEEDED (libcudart.so.13, libcupti.so.13, both found through
# libtorch's own RPATH $ORIGIN/../../nvidia/cu13/lib). About 1.2 GB and half a minute, against
# 4.7 GB for the full `pip install torch` with every CUDA library. PyPI has no CPU-only torch
# wheel; its CUDA libraries are simply never loaded here (no GPU code is run).
#
# Idempotent: once installed, a rerun only compares a stamp file and prints nothing.
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(torch==2.13.0 nvidia-cuda-runtime==13.0.96 nvidia-cuda-cupti==13.0.85)
venv=.venv
stamp="$venv/libtorch.stamp"

if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "${packages[*]}" ] \
  && [ -e "$venv/libtorch/lib/libtorch_cpu.so" ]; then
  exit 0
fi

start=$SECONDS
python=${PYTHON:-python3}
# A venv whose interpreter no longer runs (moved, or its Python removed) is rebuilt.
if [ -d "$venv" ] && ! "$venv/bin/python" -c '' 2>/dev/null; then
  rm -rf "$venv"
fi
if [ ! -d "$venv" ]; then
  "$python" -m venv "$venv"
fi
rm -f "$stamp"
"$venv/bin/python" -m pip install --quiet --no-deps --progress-bar off --no-input "${packages[@]}"

# A relative link (lib/python3.X/site-packages/torch), so config.toml needs no Python version.
site=$("$venv/bin/python" -c 'import os, sys, sysconfig; print(os.path.relpath(sysconfig.get_paths()["purelib"], sys.prefix))')
ln -sfn "$site/torch" "$venv/libtorch"
for lib in libtorch_cpu.so libc10.so; do
  if [ ! -e "$venv/libtorch/lib/$lib" ]; then
    echo "setup-libtorch: $venv/libtorch/lib/$lib missing after install" >&2
    exit 1
  fi
done
echo "${packages[*]}" >"$stamp"
echo "setup-libtorch: installed ${packages[*]} into $venv ($((SECONDS - start)) s); LIBTORCH=$venv/libtorch"
