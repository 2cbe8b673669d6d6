#!/usr/bin/env bash
# Benchmark (not a test): map pictures by projection, and the server's quick answers while large
# maps are asked for.
#  1. `raypc map` of the demo-sized synthetic mantle (64x81x128) at 1920x1080 and 4096x4096 in
#     Mollweide and Robinson, interleaved, three rounds. Target: Robinson as fast as Mollweide
#     (its inverse solved per table row, not by bisection).
#  2. `raypc serve` of the same dataset, eight clients asking for 4096x4096 Robinson maps at once
#     (POST /api/slice) while GET /api/info and /api/presets are timed. Target: /api/info within
#     100 ms; beyond one map drawing and four waiting the others are answered 503.
# Usage: bench/map_projections.sh [BUILD_DIR] [WORK_DIR]     (needs curl)
set -euo pipefail
. "$(dirname "$0")/common.sh"
bench_dirs maps "$@"
if [[ ! -f $work/ds/dataset.json ]]; then
  "$raypc" synth -o "$work/nc" --steps 2 >/dev/null
  "$raypc" preprocess "$work/nc" -o "$work/ds" --quiet --no-pathlines >/dev/null
fi
echo "machine: $(machine); load $(cut -d' ' -f1 /proc/loadavg)"
for round in 1 2 3; do
  for size in 1920x1080 4096x4096; do
    for projection in mollweide robinson; do
      /usr/bin/time -f "round $round $projection $size: %e s" \
        "$raypc" map "$work/ds" --depth 660 --projection "$projection" --size "$size" -o "$work/map.png" >/dev/null
    done
  done
done 2>&1 | grep " s$"

port=18391
"$raypc" serve "$work/ds" --port $port >"$work/serve.log" 2>&1 &
server=$!
trap 'kill $server 2>/dev/null' EXIT
for _ in $(seq 100); do curl -sf "http://127.0.0.1:$port/api/info" >/dev/null && break; sleep 0.1; done
state='{"version": 12, "image": {"width": 4096, "height": 4096}, "map": {"depthKm": 660, "projection": "robinson"}}'
pids=()
for i in 1 2 3 4 5 6 7 8; do
  curl -s -o /dev/null -w "slice $i: HTTP %{http_code} after %{time_total} s\n" -X POST -H 'Content-Type: application/json' \
    --data "$state" "http://127.0.0.1:$port/api/slice?view=map" &
  pids+=($!)
done
sleep 0.3
for k in 1 2 3 4 5 6; do
  curl -s -o /dev/null -w "GET /api/info: HTTP %{http_code} in %{time_total} s\n" "http://127.0.0.1:$port/api/info"
  curl -s -o /dev/null -w "GET /api/presets: HTTP %{http_code} in %{time_total} s\n" "http://127.0.0.1:$port/api/presets"
  sleep 0.5
done
wait "${pids[@]}"
echo "targets: Robinson within Mollweide's time; /api/info <= 0.1 s; three of eight slices 503"
