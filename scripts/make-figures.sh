#!/usr/bin/env bash
# Renders every example state (examples/*.json) into docs/images/examples/, for docs/tasks.md.
# Usage: scripts/make-figures.sh [DATASET] [SIZE]   (default: the demo dataset, 800x600)
# The demo dataset is made by scripts/demo.sh (or `raypc demo --no-serve`).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
raypc=${RAYPC:-${RAYPC_BUILD_DIR:-$root/build}/raypc}
dataset=${1:-${RAYPC_DEMO_DIR:-$root/demo-data}/dataset}
size=${2:-800x600}
[[ -x $raypc ]] || { echo "make-figures: no $raypc; build first (scripts/build.sh)" >&2; exit 1; }
[[ -f $dataset/dataset.json ]] || { echo "make-figures: no dataset at $dataset; run scripts/demo.sh or raypc demo --no-serve" >&2; exit 1; }
out=$root/docs/images/examples
mkdir -p "$out"
for state in "$root"/examples/*.json; do
  name=$(basename "$state" .json)
  "$raypc" render "$dataset" --state "$state" --size "$size" -o "$out/$name.png" >/dev/null
  echo "$out/$name.png"
done
