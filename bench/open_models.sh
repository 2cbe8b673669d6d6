#!/usr/bin/env bash
# Benchmark (not a test): opening other models than the contest's, from file to picture.
#  1. A 1 degree global tomography model in the IRIS EMC layout (25 depths x 181 x 361, one vs;
#     written by tests/data/emc-layout/write_emc_layout.py): `raypc render MODEL.nc` (preprocess
#     into a dataset beside it, then the default view at 1024x1024). Target: <= 2 s on 2 cores.
#  2. One step of a 12-cap CitcomS run of 65^3 nodes a cap (HDF5 output, written by
#     tests/data/citcoms-layout/write_citcoms.py): `raypc preprocess` resampling it onto its grid.
#     Target: <= 10 s on 2 cores.
# Three runs each, with the inputs in the page cache; prints the load before each.
# Usage: bench/open_models.sh [BUILD_DIR] [WORK_DIR]
set -euo pipefail
. "$(dirname "$0")/common.sh"
bench_dirs models "$@"
/usr/bin/python3 "$root/tests/data/emc-layout/write_emc_layout.py" "$work/emc" --grid 25x181x361
/usr/bin/python3 "$root/tests/data/citcoms-layout/write_citcoms.py" "$work/citcoms" --nodes 65x65x65 --hdf5-only
cat "$work"/emc/*.nc "$work"/citcoms/*.h5 >/dev/null
echo "machine: $(machine)"
for run in 1 2 3; do
  rm -rf "$work/emc.ds" "$work/vs.png"
  echo "load $(cut -d' ' -f1 /proc/loadavg)"
  /usr/bin/time -f "tomography 25x181x361 to a 1024^2 picture, run $run: %e s wall, %U s user, peak %M KB" \
    "$raypc" render "$work/emc/global_vs.nc" --dataset "$work/emc.ds" --size 1024x1024 -o "$work/vs.png" >/dev/null
done
for run in 1 2 3; do
  rm -rf "$work/citcoms.ds"
  echo "load $(cut -d' ' -f1 /proc/loadavg)"
  /usr/bin/time -f "CitcomS 12 x 65^3 nodes, one step resampled and preprocessed, run $run: %e s wall, %U s user, peak %M KB" \
    "$raypc" preprocess "$work/citcoms/run.0.h5" -o "$work/citcoms.ds" --quiet --no-pathlines >/dev/null
done
"$raypc" info "$work/citcoms.ds" | sed -n 2p
echo "targets: tomography <= 2 s, CitcomS step <= 10 s"
