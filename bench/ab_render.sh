#!/usr/bin/env bash
# Keeps the ray caster's speed from drifting: builds render_bench at a reference commit
# beside the working tree, then runs interleaved pairs of its main cases (reference and this tree
# in turn, the order alternating) and prints per case the median ratio this tree / reference with
# its spread. A change "within noise" of the one before shows here when several such changes add up.
#
#   bench/ab_render.sh REF [PAIRS]      e.g. bench/ab_render.sh 817b2ac 6
#
# FILTER (a regex of benchmark names) chooses the cases; the default: level-0 1024² passes of the
# benchmark view and of the default view, an interactive 512² pass, a level-2 1024² pass. The
# working tree's benchmark build is build-perf/ (as bench/render_bench.cpp says); the reference is
# built in $RAYPC_AB_DIR (default /tmp/raypc-ab) from a detached worktree of REF. Measure with
# nothing else running and say the load: ratios, not absolute times, are what compare.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
ref=${1:?usage: bench/ab_render.sh REF [PAIRS]}
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

python3 - "$out" "$pairs" <<'EOF'
import json, statistics, sys
out, pairs = sys.argv[1], int(sys.argv[2])
def times(side, i):
    with open(f"{out}/{side}-{i}.json") as f:
        return {b["name"]: b["real_time"] for b in json.load(f)["benchmarks"]}
ratios = {}
for i in range(pairs):
    ref, cur = times("ref", i), times("cur", i)
    for name in ref.keys() & cur.keys():
        ratios.setdefault(name, []).append(cur[name] / ref[name])
print(f"{'case':32} {'this tree / reference (median)':>32} {'min':>7} {'max':>7}")
for name in sorted(ratios):
    r = ratios[name]
    print(f"{name:32} {statistics.median(r):32.3f} {min(r):7.3f} {max(r):7.3f}")
EOF
