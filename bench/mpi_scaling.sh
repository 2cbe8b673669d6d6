#!/usr/bin/env bash
# Benchmark (not a test): what MPI ranks buy on this machine (docs/scaling.md).
#  1. preprocessing the 12 demo steps (64x81x128) with 1 process and with 2 ranks;
#  2. one converged 4096x4096 frame (8 passes, the default state) with 1 process and 2 ranks;
#  3. the start-up cost of the MPI-enabled binary without mpirun (`raypc info`).
# Prints wall seconds (best of RUNS), the ratio 1 process / 2 ranks and the load average.
#  4. with FULL=1 in the environment, also 4 full-resolution steps (180x201x360, ~1.7 GB of netCDF
#     and ~2.5 GB of dataset in WORK_DIR) with 1 process and 2 ranks.
# Usage: [FULL=1] bench/mpi_scaling.sh [BUILD_DIR] [WORK_DIR] [RUNS]
set -euo pipefail
. "$(dirname "$0")/common.sh"
bench_dirs mpi "$@"
runs=${3:-3}
mpirun_local=$root/scripts/mpirun-local.sh

if [[ ! -f $work/nc/spherical012.nc ]]; then
  echo "writing the 12 demo steps (64x81x128) to $work/nc" >&2
  "$raypc" synth -o "$work/nc" --steps 12 --grid 64x81x128 >/dev/null 2>&1
fi
cat "$work"/nc/*.nc >/dev/null   # into the page cache

best() {  # best LABEL COMMAND...: the least wall time of $runs runs, in seconds
  local label=$1; shift
  local t min=""
  for ((i = 0; i < runs; i++)); do
    [[ $label == preprocess* ]] && rm -rf "$work/ds-run"
    /usr/bin/time -f "%e" -o "$work/seconds" "$@" >/dev/null 2>&1
    t=$(tail -1 "$work/seconds")
    if [[ -z $min ]] || awk "BEGIN { exit !($t < $min) }"; then min=$t; fi
  done
  echo "$min"
}

echo "machine: $(machine)"
echo "load before: $(cut -d' ' -f1-3 /proc/loadavg)"
pre1=$(best preprocess "$raypc" preprocess "$work/nc" -o "$work/ds-run" --quiet)
pre2=$(best preprocess "$mpirun_local" -np 2 "$raypc" preprocess "$work/nc" -o "$work/ds-run" --quiet)
echo "preprocess 12 demo steps: 1 process $pre1 s, 2 ranks $pre2 s, ratio $(awk "BEGIN { printf \"%.2f\", $pre1 / $pre2 }")"

[[ -f $work/ds/dataset.json ]] || "$raypc" preprocess "$work/nc" -o "$work/ds" --quiet >/dev/null
frame=(render "$work/ds" --time 6 --size 4096x4096 --passes 8 -o "$work/frame.png")
ren1=$(best render "$raypc" "${frame[@]}")
ren2=$(best render "$mpirun_local" -np 2 "$raypc" "${frame[@]}")
echo "4096x4096 frame, 8 passes: 1 process $ren1 s, 2 ranks $ren2 s, ratio $(awk "BEGIN { printf \"%.2f\", $ren1 / $ren2 }")"

if [[ ${FULL:-0} == 1 ]]; then
  if [[ ! -f $work/full/spherical004.nc ]]; then
    echo "writing 4 full-resolution steps (180x201x360) to $work/full" >&2
    "$raypc" synth -o "$work/full" --steps 4 --grid 180x201x360 >/dev/null 2>&1
  fi
  cat "$work"/full/*.nc >/dev/null
  full1=$(best preprocess "$raypc" preprocess "$work/full" -o "$work/ds-run" --quiet)
  full2=$(best preprocess "$mpirun_local" -np 2 "$raypc" preprocess "$work/full" -o "$work/ds-run" --quiet)
  echo "preprocess 4 full-resolution steps: 1 process $full1 s, 2 ranks $full2 s, ratio $(awk "BEGIN { printf \"%.2f\", $full1 / $full2 }")"
  rm -rf "$work/ds-run"
fi

info=$(best info "$raypc" info "$work/ds")
echo "raypc info without mpirun (no MPI init): $info s"
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
