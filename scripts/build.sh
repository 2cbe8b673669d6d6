#!/usr/bin/env bash
# Configures (once) and builds RayPC in Release into build/. Incremental on later runs.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${RAYPC_BUILD_DIR:-$root/build}
if [[ ! -f $build/build.ninja ]]; then
  cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
fi
cmake --build "$build" -j "$(nproc)"
if [[ -f $root/web/package.json ]]; then
  "$root/scripts/build-web.sh"
fi
