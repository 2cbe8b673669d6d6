#!/usr/bin/env bash
# The first README command: install what is missing, build, make the demo data and run the demo.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/install-deps.sh"
"$root/scripts/build.sh"
exec "${RAYPC_BUILD_DIR:-$root/build}/raypc" demo --dir "${RAYPC_DEMO_DIR:-$root/demo-data}" "$@"
