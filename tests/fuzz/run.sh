#!/usr/bin/env bash
# Runs every libFuzzer target for a bounded time: tests/fuzz/run.sh BUILD_DIR SECONDS_EACH
# (BUILD_DIR as `scripts/test.sh --sanitize` makes it, default build-sanitize/; CI: 60 s each,
# bench/fuzz_long.sh: an hour each). Seeds come from tests/fuzz/corpus/<target> (and examples/
# for the state parser); what the fuzzer finds goes to BUILD_DIR/fuzz/<target>/corpus (kept
# between runs), crashes to BUILD_DIR/fuzz/<target>/crash-*. Prints one line of figures per
# target (executions, rate, coverage) and exits non-zero if any target found a crash.
# Each fuzzer is one process on one core, so the targets run side by side, as many at a time as the
# machine has cores (RAYPC_FUZZ_JOBS to set it): on 2 cores the 7 targets take 4 rounds, not 7.
set -uo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
build=$(cd "${1:-$root/build-sanitize}" && pwd)
seconds=${2:-60}
status=0
# Every target the build has (tests/fuzz/CMakeLists.txt names them), so that this list is not a second one.
targets=()
for exe in "$build"/tests/fuzz/fuzz_*; do
  [[ -x $exe && -f $exe ]] && targets+=("${exe##*/fuzz_}")
done
if ((${#targets[@]} == 0)); then
  echo "fuzz: no fuzz_* targets in $build/tests/fuzz (build with scripts/test.sh --sanitize)" >&2
  exit 1
fi
# Fuzzes one target for $seconds; its figures and findings go to $work/summary.txt, its exit
# status is the function's.
fuzz_one() {
  local target=$1 exe=$build/tests/fuzz/fuzz_$1 work=$build/fuzz/$1
  mkdir -p "$work/corpus"
  local seeds=("$root/tests/fuzz/corpus/$target")
  [[ $target == render_state ]] && seeds+=("$root/examples")
  # Small inputs: the reader's seeds are under 2 KB; a dataset manifest is larger. Leaks are
  # findings too (detect_leaks).
  local max_len=8192
  [[ $target == dataset_manifest ]] && max_len=262144
  ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1} \
  "$exe" -max_total_time="$seconds" -max_len="$max_len" -rss_limit_mb=2048 -timeout=10 -print_final_stats=1 \
    -artifact_prefix="$work/" "$work/corpus" "${seeds[@]}" > "$work/log.txt" 2>&1
  local rc=$?
  local execs rate last cov ft corpus
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$work/log.txt" | grep -o '[0-9]*$')
  rate=$(grep -o 'stat::average_exec_per_sec: *[0-9]*' "$work/log.txt" | grep -o '[0-9]*$')
  last=$(grep -E '^#[0-9]+' "$work/log.txt" | tail -1)
  cov=$(grep -o 'cov: [0-9]*' <<<"$last" | grep -o '[0-9]*')
  ft=$(grep -o 'ft: [0-9]*' <<<"$last" | grep -o '[0-9]*')
  corpus=$(grep -o 'corp: [0-9]*/[0-9]*[a-zA-Z]*' <<<"$last" | sed 's/corp: //')
  {
    printf 'fuzz %-14s %3ss: %s executions (%s/s), coverage %s edges, %s features, corpus %s, exit %d\n' \
      "$target" "$seconds" "${execs:-?}" "${rate:-?}" "${cov:-?}" "${ft:-?}" "${corpus:-?}" "$rc"
    if [[ $rc -ne 0 ]]; then
      echo "fuzz $target: finding (log $work/log.txt):"
      grep -E 'ERROR|SUMMARY|Test unit written|uncaught|==[0-9]+==' "$work/log.txt" | head -20
    fi
  } > "$work/summary.txt"
  return $rc
}

jobs_at_once=${RAYPC_FUZZ_JOBS:-$(nproc)}
if ! [[ $jobs_at_once =~ ^[1-9][0-9]*$ ]]; then
  echo "fuzz: RAYPC_FUZZ_JOBS=$jobs_at_once: expected a whole number of processes, 1 or more" >&2
  exit 2
fi
declare -A pid_of
for target in "${targets[@]}"; do
  rm -f "$build/fuzz/$target/summary.txt"
  while (($(jobs -rp | wc -l) >= jobs_at_once)); do wait -n || true; done
  fuzz_one "$target" &
  pid_of[$target]=$!
done
# The figures in the targets' order, whatever order they finished in.
for target in "${targets[@]}"; do
  wait "${pid_of[$target]}" || status=1
  cat "$build/fuzz/$target/summary.txt" 2>/dev/null || { echo "fuzz $target: wrote no figures"; status=1; }
done
exit $status
