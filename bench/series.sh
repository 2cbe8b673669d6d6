#!/usr/bin/env bash
# Benchmark (not a test): the whole series at scale (docs/scaling.md, "The whole series"). Makes N
# synthetic steps (a slab avalanche through 660 km), then times what a user with such a series waits
# for, one after the other on a machine otherwise idle, each figure with the load average (1 min):
#   1. raypc serve on the netCDF files: the first step served, the whole series preprocessed
#      (bench/serve_netcdf.mjs);
#   2. raypc preprocess, with pathlines: wall, CPU (user + system, as a share of all cores), peak
#      memory, seconds a step;
#   3. playback in the UI at 2 and 5 steps/s for two loops each (tests/browser/measure.mjs, the
#      3D view at its own size in a 1920x1080 window): steps/s and the frames shown by level; then
#      three loops at each speed over the protocol at 1500x627 (bench/playback_loops.mjs), loop by loop;
#      and step changes to a converged level-0 frame (bench/step_change.mjs);
#   4. statistics and features of a new brush and after a step change (bench/analyses_series.mjs);
# and ends with the per-step figures multiplied out to 251 steps (the SciVis 2021 contest series).
#
#   bench/series.sh [BUILD_DIR] [WORK_DIR] [--steps N] [--grid LATxRxLON] [--skip STAGE,...]
# Defaults: build/, ${TMPDIR:-/tmp}/raypc-bench-series, 24 steps, 180x201x360 (the contest's grid:
# about 10 GB of netCDF and 8 GB of dataset at 24 steps). STAGE is preprocess, serve, playback or
# analyses; a stage skipped reuses what an earlier run left in WORK_DIR. The netCDF files are kept
# between runs (remove WORK_DIR to start again).
set -euo pipefail
. "$(dirname "$0")/common.sh"
positional=() steps=24 grid=180x201x360 skip=""
while (($#)); do
  case $1 in
    --steps) steps=${2:?--steps needs a number}; shift 2 ;;
    --grid) grid=${2:?--grid needs LATxRxLON}; shift 2 ;;
    --skip) skip=${2:?--skip needs a list of stages}; shift 2 ;;
    -*) echo "series.sh: unknown option $1" >&2; exit 2 ;;
    *) positional+=("$1"); shift ;;
  esac
done
[[ $steps =~ ^[0-9]+$ ]] && ((steps >= 2)) || { echo "series.sh: --steps $steps: expected 2 or more" >&2; exit 2; }
[[ $grid =~ ^[0-9]+x[0-9]+x[0-9]+$ ]] || { echo "series.sh: --grid $grid: expected LATxRxLON" >&2; exit 2; }
for stage in ${skip//,/ }; do
  [[ $stage =~ ^(preprocess|serve|playback|analyses)$ ]] ||
    { echo "series.sh: --skip $stage: expected preprocess, serve, playback or analyses" >&2; exit 2; }
done
bench_dirs series "${positional[@]}"
command -v /usr/bin/time >/dev/null || { echo "needs /usr/bin/time (Debian package 'time')" >&2; exit 1; }
skipped() { [[ ,$skip, == *,$1,* ]]; }
load() { cut -d' ' -f1 /proc/loadavg; }
contest_steps=251

nc=$work/nc-$grid-$steps
if [[ ! -f $nc/done ]]; then
  rm -rf "$nc"
  echo "writing $steps synthetic $grid steps to $nc" >&2
  "$raypc" synth -o "$nc" --steps "$steps" --grid "$grid" --avalanche "$((steps * 5 / 6)):$((steps / 4))" >/dev/null
  touch "$nc/done"
fi
files=("$nc"/*.nc)
echo "machine: $(machine); $(free -g | awk '/^Mem:/ {print $2}') GB of memory"
echo "series: ${#files[@]} steps of $grid, $(du -sh "$nc" | cut -f1) of netCDF in $nc"
cat "${files[@]}" >/dev/null   # into the page cache: the figures are the CPU's, not the disk's
# Each stage that writes a dataset starts with none of the last one's written pages still to go to
# disk (`sync`): about 7 GB a run at 24 steps, whose writing back otherwise slows the next stage.

dataset=$work/dataset
per_step=()   # "what seconds-per-step" rows for the extrapolation
# serve first, with the last run's dataset gone: each of the two writes a dataset of about 0.3 GB a
# full-resolution step, and the inputs, the dataset of one and that of the other are more than the
# page cache of a 24 GB machine holds at 24 steps, so whichever ran second read its inputs from disk.
# serve's dataset goes when it ends (bench/serve_netcdf.mjs): both see the inputs and their own output.
skipped preprocess || rm -rf "$dataset"
if ! skipped serve; then
  sync
  echo "serve on the netCDF files (load $(load)):"
  node --experimental-websocket "$root/bench/serve_netcdf.mjs" "$build" "$work/served" 1500x627 "${files[@]}" 2>&1 |
    sed 's/^/  /' | tee "$work/serve.txt"
  whole=$(sed -n 's/.*whole series served.*: \([0-9.]*\) s.*/\1/p' "$work/serve.txt")
  [[ -n $whole ]] && per_step+=("serve $(awk -v w="$whole" -v n="$steps" 'BEGIN {print w / n}')")
  echo "  load at the end $(load)"
fi

if ! skipped preprocess; then
  cat "${files[@]}" >/dev/null
  sync
  before=$(load)
  /usr/bin/time -o "$work/time.txt" -f '%e %U %S %M' "$raypc" preprocess "${files[@]}" -o "$dataset" --quiet >/dev/null
  read -r wall user sys peak_kb < "$work/time.txt"
  cpu=$(awk -v u="$user" -v s="$sys" -v w="$wall" -v n="$(nproc)" 'BEGIN {printf "%.0f %% of %d00 %%, %.0f %% of it in the kernel", 100 * (u + s) / w, n, 100 * s / (u + s)}')
  echo "preprocess: $wall s wall ($(awk -v w="$wall" -v n="$steps" 'BEGIN {printf "%.2f", w / n}') s a step), CPU $cpu, peak $(awk -v k="$peak_kb" 'BEGIN {printf "%.2f", k / 1048576}') GB; load $before -> $(load)"
  echo "  dataset: $(du -sh "$dataset" | cut -f1), $(du -sb "$dataset" | awk -v n="$steps" '{printf "%.1f MB a step", $1 / n / 1e6}')"
  per_step+=("preprocess $(awk -v w="$wall" -v n="$steps" 'BEGIN {print w / n}')")
fi
[[ -f $dataset/dataset.json ]] || { echo "series.sh: no dataset in $dataset (run without --skip preprocess)" >&2; exit 1; }

if ! skipped playback; then
  seconds=$(((2 * steps + 1) / 2 + 2))   # two loops at 2 steps/s, four at 5
  echo "playback, 2 and 5 steps/s for $seconds s each (load $(load)):"
  node --experimental-websocket "$root/tests/browser/measure.mjs" "$raypc" "$dataset" --only-play \
    --play 2,5 --seconds "$seconds" --size view --viewport 1920x1080 2>&1 | sed 's/^/  /'
  # Loop by loop over the protocol at 1500x627 (the goal's figures: from the second loop on).
  for fps in 2 5; do
    echo "  loops at $fps steps/s, 1500x627 (bench/playback_loops.mjs; load $(load)):"
    node --experimental-websocket "$root/bench/playback_loops.mjs" "$raypc" "$dataset" --fps "$fps" --loops 3 2>&1 |
      sed 's/^/    /'
  done
  echo "  a step change to a converged level-0 frame, 1500x627 (bench/step_change.mjs, no frames rendered ahead; load $(load)):"
  node --experimental-websocket "$root/bench/step_change.mjs" "$raypc" "$dataset" -- --frame-cache 0 2>&1 | sed 's/^/    /'
  echo "  load at the end $(load)"
fi

if ! skipped analyses; then
  echo "analyses (load $(load)):"
  node "$root/bench/analyses_series.mjs" "$build" --dataset "$dataset" 2>&1 | sed 's/^/  /'
fi

if ((${#per_step[@]})); then
  echo "at $contest_steps steps (the contest series; linear in the steps, this machine):"
  for row in "${per_step[@]}"; do
    read -r what s <<<"$row"
    awk -v w="$what" -v s="$s" -v n=$contest_steps 'BEGIN {printf "  %-10s %.2f s a step -> %.1f min\n", w, s, s * n / 60}'
  done
fi
