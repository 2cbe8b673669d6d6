#!/usr/bin/env bash
# One MPI test case against the real binary: mpi_test.sh CASE RAYPC MPIRUN_LOCAL
# Every case: what `mpirun -np N raypc ...` writes equals what one `raypc ...` writes, byte for byte.
set -uo pipefail
case_name=$1 raypc=$2 mpirun_local=$3
source "$(dirname "$0")/../lib/check.sh"
make_work "mpi-$case_name"
ranks() {  # ranks N ARGS...: raypc ARGS under mpirun with N ranks
  local n=$1; shift
  "$mpirun_local" -np "$n" "$raypc" "$@"
}
# A small synthetic series (6 steps of 24x31x48) and its dataset, made by one process.
make_data() {
  "$raypc" synth -o "$work/nc" --steps 6 --grid 24x31x48 >/dev/null 2>&1
  "$raypc" preprocess "$work/nc" -o "$work/ds" --quiet --sample-rows 2000 >/dev/null
}
# die_run PHASE N ARGS...: raypc ARGS on N ranks with rank 1 dying at PHASE (the test hook,
# docs/scaling.md), bounded by a timeout; output in $work/out, exit status in $status.
die_run() {
  local phase=$1 n=$2; shift 2
  RAYPC_TEST_DIE_RANK=1 RAYPC_TEST_DIE_AT=$phase timeout 120 "$mpirun_local" -np "$n" "$raypc" "$@" >"$work/out" 2>&1
  status=$?
}
ended_with_error() {  # ended_with_error WHAT: the last run failed, and not by the timeout (124)
  check "$1: non-zero status ($status), not a hang" test "$status" -ne 0 -a "$status" -ne 124
}
# same_tree A B: the same files with the same bytes (the lock file aside).
same_tree() {
  diff -r --exclude=.lock "$1" "$2" >/dev/null
}

case $case_name in
stats)
  make_data
  sel=(--range "depth=0:660" --range "temperature anomaly=100:1000")
  "$raypc" stats "$work/ds" "${sel[@]}" -o "$work/s1.csv" --profile "$work/p1.csv" --hovmoller "$work/h1.png" --quiet >/dev/null
  for n in 2 3; do
    ranks "$n" stats "$work/ds" "${sel[@]}" -o "$work/s$n.csv" --profile "$work/p$n.csv" --hovmoller "$work/h$n.png" \
      --quiet >"$work/out$n" 2>&1
    check "stats with $n ranks exits 0" test $? -eq 0
    check "stats with $n ranks: the same CSV as one process" cmp -s "$work/s1.csv" "$work/s$n.csv"
    check "stats with $n ranks: the same time-depth picture as one process" cmp -s "$work/h1.png" "$work/h$n.png"
    check "stats with $n ranks: the same profile as one process" cmp -s "$work/p1.csv" "$work/p$n.csv"
    check "stats with $n ranks reports once" test "$(grep -c 'selected volume of 6 steps' "$work/out$n")" -eq 1
  done
  # 7 ranks for 6 steps: a rank without a step still takes part.
  ranks 7 stats "$work/ds" "${sel[@]}" -o "$work/s7.csv" --time 1:4 --quiet >/dev/null 2>&1
  "$raypc" stats "$work/ds" "${sel[@]}" -o "$work/s1b.csv" --time 1:4 --quiet >/dev/null
  check "stats of 4 steps on 7 ranks: the same CSV" cmp -s "$work/s1b.csv" "$work/s7.csv"
  # raypc features shares its steps out the same way: the same file, byte for byte.
  "$raypc" features "$work/ds" "${sel[@]}" -o "$work/f1.csv" --quiet >/dev/null
  ranks 3 features "$work/ds" "${sel[@]}" -o "$work/f3.csv" --quiet >"$work/fout3" 2>&1
  check "features with 3 ranks exits 0" test $? -eq 0
  check "features with 3 ranks: the same CSV as one process" cmp -s "$work/f1.csv" "$work/f3.csv"
  check "features found some ($(($(wc -l < "$work/f1.csv") - 1)) rows)" test "$(wc -l < "$work/f1.csv")" -gt 6
  # Tracking: each rank finds and links the features of its steps (and the step before them), rank 0
  # follows the tracks: the same files again.
  "$raypc" features "$work/ds" "${sel[@]}" -o "$work/g1.csv" --tracks "$work/t1.csv" --events "$work/e1.csv" \
    --stalls "$work/st1.csv" --stall-by deepest --quiet >/dev/null
  check "features --tracks found tracks ($(($(wc -l < "$work/t1.csv") - 1)) rows)" test "$(wc -l < "$work/t1.csv")" -gt 6
  for n in 2 3; do
    ranks $n features "$work/ds" "${sel[@]}" -o "$work/g$n.csv" --tracks "$work/t$n.csv" --events "$work/e$n.csv" \
      --stalls "$work/st$n.csv" --stall-by deepest --quiet >/dev/null 2>&1
    check "features --tracks/--events/--stalls with $n ranks: the same four files" \
      bash -c "cmp -s '$work/g1.csv' '$work/g$n.csv' && cmp -s '$work/t1.csv' '$work/t$n.csv' && cmp -s '$work/e1.csv' '$work/e$n.csv' && cmp -s '$work/st1.csv' '$work/st$n.csv' && cmp -s '$work/f1.csv' '$work/g1.csv'"
  done
  ;;
errors)
  make_data
  # An error every rank meets is printed once (by rank 0), with a non-zero status, nothing written.
  ranks 2 stats "$work/ds" --range "pressure=0:1" -o "$work/x.csv" >"$work/out" 2>&1
  status=$?
  check "bad --range under mpirun: non-zero status ($status)" test $status -ne 0
  check "bad --range: one error line naming the variable" \
    test "$(grep -c "raypc: error: --range\[0\] (pressure): unknown variable" "$work/out")" -eq 1
  check "bad --range: no other raypc error line" test "$(grep -c 'raypc: error' "$work/out")" -eq 1
  check "bad --range: nothing written" test ! -e "$work/x.csv"
  # Damage that only shows in one step's data (step 5 of 6 has no value of temperature: NaN
  # everywhere): the rank that takes it fails, the others stop taking steps, every rank stops with
  # the one message, printed once; the steps finished by any rank stay for a rerun.
  mkdir -p "$work/bad"; cp "$work"/nc/*.nc "$work/bad/"
  "${RAYPC_PYTHON:-/usr/bin/python3}" -c "
import netCDF4, numpy, sys
with netCDF4.Dataset(sys.argv[1], 'a') as nc:
    nc.variables['temperature'][:] = numpy.nan" "$work/bad/spherical005.nc"
  ranks 3 preprocess "$work/bad" -o "$work/dsbad" --quiet --sample-rows 2000 >"$work/out" 2>&1
  status=$?
  check "a step without temperature on 3 ranks: non-zero status ($status)" test $status -ne 0
  check "a step without temperature: one error line naming the file, the variable and the finished steps" \
    test "$(grep -c 'raypc: error: .*spherical005.nc: temperature: every value of the step is missing.*finished steps stay in' "$work/out")" -eq 1
  check "a step without temperature: no other raypc error line" test "$(grep -c 'raypc: error' "$work/out")" -eq 1
  check "a step without temperature: the dataset says it did not finish" \
    grep -q '"status": "incomplete"' "$work/dsbad/dataset.json"
  check "a step without temperature: step 4 (the bad file) was not written" test ! -e "$work/dsbad/steps/0004"
  # A command that is not shared out runs once, on rank 0.
  ranks 3 info "$work/ds" >"$work/info" 2>&1
  check "info under 3 ranks prints once" test "$(grep -c '(RayPC dataset' "$work/info")" -eq 1
  # The demo runs in one process: refused with one line, at once, nothing made.
  timeout 60 "$mpirun_local" -np 2 "$raypc" demo --dir "$work/demo" --no-serve >"$work/demo.out" 2>&1
  status=$?
  ended_with_error "demo under 2 ranks is refused"
  check "demo under 2 ranks: one error line saying why" \
    test "$(grep -c 'raypc: error: demo: runs in one process' "$work/demo.out")" -eq 1
  check "demo under 2 ranks: nothing made" test ! -e "$work/demo"
  # A distributed server whose dataset cannot be opened: every rank stops, one error line.
  timeout 60 "$mpirun_local" -np 2 "$raypc" serve "$work/missing" --port 0 >"$work/serve" 2>&1
  status=$?
  ended_with_error "serve of a missing dataset under 2 ranks"
  check "serve of a missing dataset under 2 ranks: one error line naming it" \
    test "$(grep -c "raypc: error: .*$work/missing" "$work/serve")" -eq 1
  check "serve of a missing dataset under 2 ranks: no other raypc error line" \
    test "$(grep -c 'raypc: error' "$work/serve")" -eq 1
  # netCDF files are served by one process only: under mpirun one error line, nothing written.
  timeout 60 "$mpirun_local" -np 2 "$raypc" serve "$work"/nc/spherical00{1,2}.nc --dataset "$work/nc-series" \
    --port 0 >"$work/serve-nc" 2>&1
  status=$?
  ended_with_error "serve of netCDF files under 2 ranks"
  check "serve of netCDF files under 2 ranks: one error line saying to preprocess first" \
    test "$(grep -c 'raypc: error: serving netCDF files is for one process' "$work/serve-nc")" -eq 1
  check "serve of netCDF files under 2 ranks: no other raypc error line" \
    test "$(grep -c 'raypc: error' "$work/serve-nc")" -eq 1
  check "serve of netCDF files under 2 ranks: nothing written" test ! -e "$work/nc-series"
  ;;
render_frames)
  make_data
  view=(--size 96x64 --passes 3 --legend --reference shells)
  "$raypc" render "$work/ds" --time 0:5 -o "$work/one/f_%02d.png" --depth "$work/one/d_%02d.pfm" "${view[@]}"
  for n in 2 3; do
    ranks "$n" render "$work/ds" --time 0:5 -o "$work/n$n/f_%02d.png" --depth "$work/n$n/d_%02d.pfm" "${view[@]}" \
      --stats >"$work/stats$n.json" 2>"$work/err$n"
    check "6 frames on $n ranks exit 0" test $? -eq 0
    check "6 frames on $n ranks: the same PNGs and depths as one process" same_tree "$work/one" "$work/n$n"
    check "6 frames on $n ranks: rank 0 prints the statistics of all 6, in step order" \
      test "$(grep -o '"step": [0-9]*' "$work/stats$n.json" | tr -dc '0-9')" = 012345
  done
  check "no temporary files left" test "$(find "$work/n2" "$work/n3" -name '.*' | wc -l)" -eq 0
  ;;
render_tiles)
  make_data
  # 200x150 is 7x5 tiles of 32 pixels, the last row and column partial: tiles of every shape go
  # to every rank, and the frame is gathered from the accumulated sums.
  view=(--time 2 --size 200x150 --passes 4 --legend --reference shells --reference graticule)
  "$raypc" render "$work/ds" "${view[@]}" -o "$work/one.png" --depth "$work/one.pfm" --stats >"$work/one.json"
  for n in 2 3; do
    ranks "$n" render "$work/ds" "${view[@]}" -o "$work/n$n.png" --depth "$work/n$n.pfm" --stats \
      >"$work/n$n.json" 2>"$work/err$n"
    check "one frame on $n ranks exits 0" test $? -eq 0
    check "one frame on $n ranks: the same PNG as one process" cmp -s "$work/one.png" "$work/n$n.png"
    check "one frame on $n ranks: the same depth as one process" cmp -s "$work/one.pfm" "$work/n$n.pfm"
    check "one frame on $n ranks: the statistics say $n ranks" grep -q "\"ranks\": $n" "$work/n$n.json"
    check "one frame on $n ranks: the ranks' samples add up to one process's" \
      test "$(grep '^  "samples"' "$work/n$n.json")" = "$(grep '^  "samples"' "$work/one.json")"
  done
  ;;
preprocess)
  "$raypc" synth -o "$work/nc" --steps 8 --grid 24x31x48 >/dev/null 2>&1
  "$raypc" preprocess "$work/nc" -o "$work/ds1" --quiet --sample-rows 2000 >/dev/null
  for n in 2 3; do
    ranks "$n" preprocess "$work/nc" -o "$work/ds$n" --sample-rows 2000 >"$work/out$n" 2>"$work/err$n"
    check "preprocess on $n ranks exits 0" test $? -eq 0
    check "preprocess on $n ranks: dataset.json, arrays, sample and pathlines equal one process's" \
      same_tree "$work/ds1" "$work/ds$n"
    check "preprocess on $n ranks: one summary" test "$(grep -c '8 steps (8 written, 0 already done)' "$work/out$n")" -eq 1
    check "preprocess on $n ranks: progress once, by rank 0" \
      test "$(grep -c '^preprocess: 8/8 steps' "$work/err$n")" -eq 1
  done
  # The files really hold data (two datasets of empty files would compare equal too).
  check "the dataset is complete" grep -q '"status": "complete"' "$work/ds3/dataset.json"
  check "step 7's temperature holds 24x31x48 u16 values" \
    test "$(stat -c %s "$work/ds3/steps/0007/L0/temperature.u16")" -eq $((24 * 31 * 48 * 2))
  ;;
preprocess_aspect)
  # An ASPECT series (deal.II's files, tests/data/aspect-layout) resampled on 2 ranks, the
  # steps shared out as for netCDF: the same dataset as one process's.
  series=$(cd "$(dirname "$0")/../data/aspect-layout/shell-lagrange" && pwd)
  "$raypc" preprocess "$series" -o "$work/ds1" --quiet --sample-rows 2000 >/dev/null
  ranks 2 preprocess "$series" -o "$work/ds2" --quiet --sample-rows 2000 >"$work/out2" 2>&1
  status=$?
  check "preprocess of an ASPECT series on 2 ranks exits 0: $(cat "$work/out2")" test "$status" -eq 0
  check "on 2 ranks: the same files as one process's" same_tree "$work/ds1" "$work/ds2"
  check "both steps, resampled" test "$(grep -c '"origin"' "$work/ds2/dataset.json")" -ge 2
  ;;
preprocess_resume)
  "$raypc" synth -o "$work/nc" --steps 8 --grid 24x31x48 >/dev/null 2>&1
  "$raypc" preprocess "$work/nc" -o "$work/ds1" --quiet --sample-rows 2000 >/dev/null
  # Rank 1 dies after its first step (a test hook, docs/scaling.md): the job stops, no hang.
  die_run preprocess-step 2 preprocess "$work/nc" -o "$work/ds2" --quiet --sample-rows 2000
  ended_with_error "a rank that dies stops the run"
  check "the dying rank is named" grep -q "rank 1 exits" "$work/out"
  check "the dataset says it did not finish" grep -q '"status": "incomplete"' "$work/ds2/dataset.json"
  finished=$(ls "$work/ds2/steps" | grep -c '^[0-9]*$')
  check "finished steps stay ($finished)" test "$finished" -ge 1
  # How many steps rank 0 finishes before mpirun ends it depends on the machine's load: make the
  # rerun's work certain by taking two finished steps away (as if the run had died before them).
  rm -rf "$work/ds2/steps/0002" "$work/ds2/steps/0005"
  finished=$(ls "$work/ds2/steps" | grep -c '^[0-9]*$')
  ranks 2 preprocess "$work/nc" -o "$work/ds2" --quiet --sample-rows 2000 >"$work/out2" 2>&1
  check "the rerun on 2 ranks exits 0" test $? -eq 0
  check "the rerun resumes ($(grep -o '[0-9]* written, [0-9]* already done' "$work/out2"))" \
    grep -q "$((8 - finished)) written, $finished already done" "$work/out2"
  check "the resumed dataset equals one process's" same_tree "$work/ds1" "$work/ds2"
  ;;
rank_dies)
  make_data
  # A rank that dies in the pathline phase and one that dies while rendering frames: the job ends
  # with an error within the timeout instead of waiting for the dead rank.
  die_run preprocess-pathlines 3 preprocess "$work/nc" -o "$work/dsx" --quiet --sample-rows 2000
  ended_with_error "preprocess: a rank dying before the pathlines ends the job"
  check "preprocess: the dataset is not marked complete" grep -q '"status": "incomplete"' "$work/dsx/dataset.json"
  die_run render-frame 2 render "$work/ds" --time 1 --size 128x96 --passes 2 -o "$work/x.png"
  ended_with_error "render: a rank dying before its tiles are gathered ends the job"
  check "render: no picture written" test ! -e "$work/x.png"
  ;;
*)
  echo "unknown case $case_name"; exit 2
  ;;
esac

if ((failures)); then echo "$failures check(s) failed"; exit 1; fi
echo "all checks passed"
