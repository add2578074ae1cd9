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
# The install is shared by every checkout of this user: it lives in
# ${GRASPMAP_CACHE_DIR:-${XDG_CACHE_HOME:-~/.cache}/graspmap}/libtorch-<packages hash>/, and .venv
# is a link to it, so a fresh clone (CI's, say) only makes the link. A lock keeps two checkouts
# from installing at once, and the install is renamed into place only when complete. A .venv that
# is a real directory from an earlier layout is kept as long as it is complete.
#
# Idempotent: once installed, a rerun only compares a stamp file and prints nothing.
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(torch==2.13.0 nvidia-cuda-runtime==13.0.96 nvidia-cuda-cupti==13.0.85)
venv=.venv

complete() {
  [ -f "$1/libtorch.stamp" ] && [ "$(cat "$1/libtorch.stamp")" = "${packages[*]}" ] \
    && [ -e "$1/libtorch/lib/libtorch_cpu.so" ]
}

if complete "$venv"; then
  exit 0
fi

cache=${GRASPMAP_CACHE_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/graspmap}
key=$(printf '%s\n' "${packages[@]}" | sha256sum | cut -c1-16)
shared="$cache/libtorch-$key"
mkdir -p "$cache"
start=$SECONDS
installed=""
{
  flock 9
  if ! complete "$shared"; then
    python=${PYTHON:-python3}
    staging="$shared.partial-$$"
    rm -rf "$staging"
    "$python" -m venv "$staging"
    "$staging/bin/python" -m pip install --quiet --no-deps --progress-bar off --no-input "${packages[@]}"
    # A relative link (lib/python3.X/site-packages/torch), so config.toml needs no Python version.
    site=$("$staging/bin/python" -c 'import os, sys, sysconfig; print(os.path.relpath(sysconfig.get_paths()["purelib"], sys.prefix))')
    ln -sfn "$site/torch" "$staging/libtorch"
    for lib in libtorch_cpu.so libc10.so; do
      if [ ! -e "$staging/libtorch/lib/$lib" ]; then
        echo "setup-libtorch: $staging/libtorch/lib/$lib missing after install" >&2
        exit 1
      fi
    done
    echo "${packages[*]}" >"$staging/libtorch.stamp"
    rm -rf "$shared"
    mv "$staging" "$shared"
    installed=yes
  fi
} 9>"$cache/libtorch-$key.lock"

# An incomplete real directory from an earlier layout gives way to the link.
if [ -e "$venv" ] && [ ! -L "$venv" ]; then
  rm -rf "$venv"
fi
ln -sfn "$shared" "$venv"
if [ -n "$installed" ]; then
  echo "setup-libtorch: installed ${packages[*]} into $shared ($((SECONDS - start)) s); LIBTORCH=$venv/libtorch"
else
  echo "setup-libtorch: linked $venv to the installed $shared; LIBTORCH=$venv/libtorch"
fi
