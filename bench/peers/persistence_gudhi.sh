#!/usr/bin/env bash
# Benchmark and cross-check (not a test): RayPC's persistence pairs against GUDHI's (Debian's
# python3-gudhi, an independent library), on the same complex and the same field: the temperature
# anomaly of one synthetic step (default the demo's 64x81x128). bench/peers/persistence_gudhi.py
# builds the Freudenthal 1-skeleton as a lower-star filtration and compares the pairs' values;
# this script prints both times. Installs python3-gudhi (apt-get) if missing.
# Usage: bench/peers/persistence_gudhi.sh [BUILD_DIR] [GRID=64x81x128]
set -euo pipefail
. "$(dirname "$0")/../common.sh"
build=${1:-$root/build}
grid=${2:-64x81x128}
work=${WORK:-/tmp/raypc-persistence-peer}
raypc=$build/raypc
[[ -x $raypc ]] || { echo "no $raypc: build first (cmake --build $build --target raypc)" >&2; exit 1; }
py=/usr/bin/python3  # Debian's, where python3-gudhi installs (a python3 earlier on PATH may not see it)
if ! $py -c "import gudhi, numpy" 2>/dev/null; then
  echo "installing python3-gudhi (apt-get)" >&2
  DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends python3-gudhi python3-numpy \
    >"$work.apt.log" 2>&1 || { echo "MISSING: could not install python3-gudhi (see $work.apt.log)" >&2; exit 1; }
fi

mkdir -p "$work"
if [[ ! -f $work/$grid/dataset.json ]]; then
  "$raypc" synth -o "$work/nc-$grid" --steps 1 --grid "$grid" >/dev/null
  "$raypc" preprocess "$work/nc-$grid" -o "$work/$grid" --no-pathlines --encoding float32 --quiet >/dev/null  # gudhi reads the .f32 array
fi
IFS=x read -r nlat nr nlon <<<"$grid"
echo "machine: $(machine)"
echo "field: temperature anomaly, step 0 of the synthetic model, $grid (lat x r x lon)"
start=$(date +%s.%N)
"$raypc" export "$work/$grid" --time 0 --what persistence -o "$work/diagram.csv"
end=$(date +%s.%N)
echo "RESULT raypc_export_s $(echo "$end - $start" | bc)   (load the step, all pairs, write the CSV)"
$py "$root/bench/peers/persistence_gudhi.py" "$work/$grid/steps/0000/L0/temperature_anomaly.f32" \
  "$nlat" "$nr" "$nlon" "$work/diagram.csv"
