#!/usr/bin/env bash
# Keeps the ray caster's speed from drifting: builds render_bench at a reference commit
# beside the working tree, then runs interleaved pairs of its main cases (reference and this tree
# in turn, the order alternating) and prints per case the median ratio this tree / reference with
# its spread. A change "within noise" of the one before shows here when several such changes add up.
#
#   bench/ab_render.sh [REF] [PAIRS]    e.g. bench/ab_render.sh 817b2ac 6
#
# REF defaults to the stored reference, bench/ab_reference (the commit whose level-0 pass the kernel
# must not fall behind; docs/rendering.md "Performance"). Run it before a change to the kernel
# lands (src/render/render_kernel*, volume_renderer.cpp, skip_grid.cpp). With LIMIT (e.g. LIMIT=1.03)
# the script exits 1 when BM_Level0Pass1024's median CPU ratio is above it.
#
# FILTER (a regex of benchmark names) chooses the cases; the default: level-0 1024² passes of the
# benchmark view and of the default view, an interactive 512² pass, a level-2 1024² pass. The
# working tree's benchmark build is build-perf/ (as bench/render_bench.cpp says); the reference is
# built in $RAYPC_AB_DIR (default /tmp/raypc-ab) from a detached worktree of REF. Measure with
# nothing else running and say the load: ratios, not absolute times, are what compare.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
ref=${1:-$(sed -n 's/^commit //p' "$root/bench/ab_reference")}
pairs=${2:-6}
filter=${FILTER:-'^BM_(Level0Pass1024|DefaultViewPass1024|InteractivePass512|Level2Pass1024)$'}
work=${RAYPC_AB_DIR:-/tmp/raypc-ab}
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)

build_bench() {  # SOURCE BUILD
  if [[ ! -f $2/build.ninja ]]; then
    cmake -S "$1" -B "$2" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_UNITY_BUILD=ON -DRAYPC_BUILD_BENCH=ON \
      -DRAYPC_BUILD_TESTS=OFF "${launcher[@]}" >/dev/null
  fi
  cmake --build "$2" --target render_bench >/dev/null
}

mkdir -p "$work"
sha=$(git -C "$root" rev-parse --verify "$ref^{commit}")
if [[ ! -d $work/src/.git && ! -f $work/src/.git ]]; then
  git -C "$root" worktree add --detach "$work/src" "$sha" >/dev/null
else
  git -C "$work/src" checkout -q --detach "$sha"
fi
echo "ab_render: building the reference $ref (${sha:0:10}) in $work/build and this tree in build-perf" >&2
build_bench "$work/src" "$work/build"
build_bench "$root" "$root/build-perf"

out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for ((i = 0; i < pairs; ++i)); do
  sides=(ref cur)
  ((i % 2)) && sides=(cur ref)
  for side in "${sides[@]}"; do
    exe=$work/build/bench/render_bench
    [[ $side == cur ]] && exe=$root/build-perf/bench/render_bench
    "$exe" --benchmark_filter="$filter" --benchmark_format=json --benchmark_min_time=0.5 >"$out/$side-$i.json" 2>/dev/null
  done
  echo "ab_render: pair $((i + 1)) of $pairs done (load $(cut -d' ' -f1 /proc/loadavg))" >&2
done

python3 - "$out" "$pairs" "${LIMIT:-}" <<'EOF'
import json, statistics, sys
out, pairs, limit = sys.argv[1], int(sys.argv[2]), sys.argv[3]
# Wall time per pass, and CPU time per pass per thread: the second is steadier when the machine
# is shared (another process's work does not count), so the limit is checked on it.
def times(side, i):
    with open(f"{out}/{side}-{i}.json") as f:
        return {b["name"]: (b["real_time"], b["cpu_ms/pass/thread"]) for b in json.load(f)["benchmarks"]}
wall, cpu = {}, {}
for i in range(pairs):
    ref, cur = times("ref", i), times("cur", i)
    for name in ref.keys() & cur.keys():
        wall.setdefault(name, []).append(cur[name][0] / ref[name][0])
        cpu.setdefault(name, []).append(cur[name][1] / ref[name][1])
print(f"{'case':26} {'this tree / reference: wall (median, min, max)':>46} {'cpu/thread (median, min, max)':>32}")
for name in sorted(wall):
    w, c = wall[name], cpu[name]
    print(f"{name:26} {statistics.median(w):24.3f} {min(w):10.3f} {max(w):10.3f} {statistics.median(c):12.3f} {min(c):9.3f} {max(c):9.3f}")
if limit:
    level0 = statistics.median(cpu["BM_Level0Pass1024"])
    if level0 > float(limit):
        print(f"ab_render: BM_Level0Pass1024 takes {level0:.3f} x the reference's CPU time, above LIMIT={limit}")
        sys.exit(1)
EOF
