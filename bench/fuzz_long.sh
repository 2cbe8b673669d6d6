#!/usr/bin/env bash
# Long fuzzing (not a test): every libFuzzer target for an hour (or SECONDS each), on top of the
# corpus earlier runs found. CI runs the same for 60 s each (.ci/run). Figures: docs/reliability.md.
# Usage: bench/fuzz_long.sh [SECONDS_EACH] [BUILD_DIR]   (BUILD_DIR from scripts/test.sh --sanitize)
set -euo pipefail
. "$(dirname "$0")/common.sh"
build=${2:-$root/build-sanitize}
[[ -x $build/tests/fuzz/fuzz_protocol ]] || { echo "no fuzz targets in $build: run scripts/test.sh --sanitize first" >&2; exit 1; }
echo "machine: $(machine)"
exec "$root/tests/fuzz/run.sh" "$build" "${1:-3600}"
