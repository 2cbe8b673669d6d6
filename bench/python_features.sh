#!/usr/bin/env bash
# Benchmark (not a test): `raypc features` over the demo dataset with the task-1 state
# (examples/task1-slabs-660km.json: slabs at 660 km, 12 steps), from the CLI and from Python
# (raypc.open(...).features(state)), which should be as fast: both get their big arrays on
# transparent huge pages from the library (core/huge_pages.h), not from how the process started.
# Variants, run interleaved (A B C ... A B C ...) so that a change of load on a shared machine hits
# all of them alike:
#   cli            build/raypc features as it runs: it runs itself again with glibc's malloc asking
#                  for huge pages (GLIBC_TUNABLES=glibc.malloc.hugetlb=1) and the library asks too
#   cli-library    GLIBC_TUNABLES=glibc.malloc.hugetlb=0: the library's asking alone, as in Python
#   cli-tunable    RAYPC_HUGE_PAGES=0 GLIBC_TUNABLES=glibc.malloc.hugetlb=1: the tunable alone, the
#                  CLI as it was before the library asked (the baseline: the CLI must not be slower)
#   cli-4k         RAYPC_HUGE_PAGES=0: 4 KB pages
#   python         open + features inside python3 (import excluded: it is not the command's work),
#                  progress off
#   python-4k      the same with RAYPC_HUGE_PAGES=0
# Each run's wall seconds and CPU seconds (user + system, all threads): on a shared machine of two
# cores the wall time depends on whether the second core is free, the CPU time much less. Prints
# the medians and their ratios to `cli`; the goal is python within 10 % of cli.
# Makes the demo dataset first when WORK/demo has none (`raypc demo --no-serve`).
# Usage: bench/python_features.sh [BUILD_DIR] [WORK_DIR] [RUNS (default 7)]
set -euo pipefail
. "$(dirname "$0")/common.sh"
bench_dirs python-features "${1:-}" "${2:-}"
runs=${3:-7}
[[ -d $build/python/raypc ]] || { echo "no $build/python/raypc: build the _raypc target first" >&2; exit 1; }
dataset=$work/demo/dataset
state=$root/examples/task1-slabs-660km.json
[[ -f $dataset/dataset.json ]] || "$raypc" demo --no-serve --dir "$work/demo" >/dev/null

# python_features [ENV...]: "WALL CPU ROWS" of one open + features in python3.
python_features() {
  env "$@" PYTHONPATH="$build/python" /usr/bin/python3 - "$dataset" "$state" <<'PY'
import sys, time
import raypc, pandas  # imported before the clocks start
wall, cpu = time.perf_counter(), time.process_time()
table = raypc.open(sys.argv[1]).features(sys.argv[2], progress=False)
print(f"{time.perf_counter() - wall:.3f} {time.process_time() - cpu:.3f} {len(table)}")
PY
}
# cli [ENV...]: "WALL CPU" of one `raypc features`.
cli() {
  env "$@" /usr/bin/time -f "%e %U %S" -o "$work/time" "$raypc" features "$dataset" --state "$state" \
    -o "$work/features.csv" --quiet >/dev/null 2>&1
  awk '{printf "%.2f %.2f\n", $1, $2 + $3}' "$work/time"
}
# seconds VARIANT: "WALL CPU" of one run of VARIANT.
seconds() {
  case $1 in
    cli) cli ;;
    cli-library) cli GLIBC_TUNABLES=glibc.malloc.hugetlb=0 ;;
    cli-tunable) cli RAYPC_HUGE_PAGES=0 GLIBC_TUNABLES=glibc.malloc.hugetlb=1 ;;
    cli-4k) cli RAYPC_HUGE_PAGES=0 ;;
    python) python_features | cut -d' ' -f1,2 ;;
    python-4k) python_features RAYPC_HUGE_PAGES=0 | cut -d' ' -f1,2 ;;
  esac
}
variants=(cli cli-library cli-tunable cli-4k python python-4k)
echo "machine: $(machine); THP: $(cat /sys/kernel/mm/transparent_hugepage/enabled)"
echo "features of $state over $dataset ($(python_features | cut -d' ' -f3) rows), $runs runs each"
cat "$dataset"/*/* >/dev/null 2>&1 || true  # into the page cache
declare -A walls cpus
for run in $(seq "$runs"); do
  line="run $run, load $(cut -d' ' -f1 /proc/loadavg), wall/cpu s:"
  for v in "${variants[@]}"; do
    read -r w c <<<"$(seconds "$v")"
    walls[$v]+="$w "
    cpus[$v]+="$c "
    line+=" $v $w/$c"
  done
  echo "$line"
done
median() { tr ' ' '\n' <<<"$1" | grep . | sort -g | awk '{a[NR]=$1} END {print (NR % 2 ? a[(NR+1)/2] : (a[NR/2] + a[NR/2+1]) / 2)}'; }
ratio() { awk -v a="$1" -v b="$2" 'BEGIN {printf "%.2f", a / b}'; }
wall0=$(median "${walls[cli]}") cpu0=$(median "${cpus[cli]}")
for v in "${variants[@]}"; do
  w=$(median "${walls[$v]}") c=$(median "${cpus[$v]}")
  echo "median $v: wall $w s ($(ratio "$w" "$wall0") x cli), cpu $c s ($(ratio "$c" "$cpu0") x cli)"
done
echo "load now: $(cut -d' ' -f1-3 /proc/loadavg)"
echo "goals: python <= 1.10 x cli; cli <= 1.00 x cli-tunable (the CLI as it was)"
