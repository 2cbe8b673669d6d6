#!/usr/bin/env bash
# Benchmark (not a test): preprocess one full-resolution 180x201x360 step with the file in the
# page cache; prints wall seconds and peak memory of `raypc preprocess`.
# Targets (2 cores): <= 5 s and <= 2.5 GB.
# Usage: bench/preprocess_full_step.sh [BUILD_DIR] [WORK_DIR]
set -euo pipefail
. "$(dirname "$0")/common.sh"
bench_dirs full "$@"
command -v /usr/bin/time >/dev/null || { echo "needs /usr/bin/time (Debian package 'time')" >&2; exit 1; }

if [[ ! -f $work/nc/spherical001.nc ]]; then
  echo "writing one synthetic 180x201x360 step to $work/nc" >&2
  "$raypc" synth -o "$work/nc" --steps 1 --grid 180x201x360 >/dev/null
fi
cat "$work/nc/spherical001.nc" >/dev/null   # into the page cache
echo "machine: $(machine)"
echo "input: $(du -h "$work/nc/spherical001.nc" | cut -f1) $work/nc/spherical001.nc"
for run in 1 2 3; do
  rm -rf "$work/dataset"
  /usr/bin/time -f "run $run: %e s wall, %U s user, %S s sys, peak %M KB" \
    "$raypc" preprocess "$work/nc/spherical001.nc" -o "$work/dataset" --quiet >/dev/null
done
echo "output: $(du -sh "$work/dataset" | cut -f1)"
echo "targets: <= 5 s, <= 2.5 GB (2621440 KB)"
