#!/usr/bin/env bash
# Soak benchmark (not a test): N clients change their state for M minutes against `raypc serve` on
# loopback (tests/protocol/soak.cpp); prints frames per client, frame latency p50/p99, the longest
# time a client went without a frame, /api/info latency and the server's peak anonymous memory.
# Two runs: clients that send as fast as the connection takes states (overload), and clients at
# 60 states a second (a user dragging). The short version is the ctest case server.soak_short.
# Usage: bench/soak/run.sh [BUILD_DIR] [WORK_DIR]   (env: CLIENTS=8 MINUTES=3 SIZE=512x512 GRID=90x101x180)
set -euo pipefail
. "$(dirname "$0")/../common.sh"
bench_dirs soak "$@"
clients=${CLIENTS:-8}
minutes=${MINUTES:-3}
size=${SIZE:-512x512}
grid=${GRID:-90x101x180}
soak=$build/tests/protocol/raypc_soak
[[ -x $soak ]] || { echo "no $soak: build first (with tests)" >&2; exit 1; }

# A synthetic dataset of 6 steps (the soak needs a directory named ds).
if [[ ! -f $work/ds/dataset.json ]]; then
  echo "writing 6 synthetic $grid steps to $work/nc and preprocessing them" >&2
  "$raypc" synth -o "$work/nc" --steps 6 --grid "$grid" >/dev/null
  "$raypc" preprocess "$work/nc" -o "$work/ds" --quiet >/dev/null
fi
echo "machine: $(machine)"
seconds=$((minutes * 60))
bounds=(--max-gap-s 5 --max-info-ms 2000)
echo "== overload: states as fast as the connection takes them"
"$soak" --raypc "$raypc" --dataset "$work/ds" --clients "$clients" --seconds "$seconds" --size "$size" "${bounds[@]}" || true
echo "== 60 states a second per client"
"$soak" --raypc "$raypc" --dataset "$work/ds" --clients "$clients" --seconds "$seconds" --size "$size" \
  --interval-ms 16 "${bounds[@]}" || true
