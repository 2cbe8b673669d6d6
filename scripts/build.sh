#!/usr/bin/env bash
# Configures (once) and builds RayPC in Release into build/. Incremental on later runs.
# A unity build (CMAKE_UNITY_BUILD: the sources of a target compiled in batches, each header parsed
# once per batch) took 260 s where a file-by-file build took 451 s on a fresh machine
# (docs/reliability.md, "Time of a CI run"); file-local names must differ between a target's files.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${RAYPC_BUILD_DIR:-$root/build}
# ccache, where installed, makes a rebuild in a second clone or worktree quick.
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
if [[ ! -f $build/build.ninja ]]; then
  cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_UNITY_BUILD=ON "${launcher[@]}" >/dev/null
fi
cmake --build "$build" -j "$(nproc)"
if [[ -f $root/web/package.json ]]; then
  "$root/scripts/build-web.sh"
fi
