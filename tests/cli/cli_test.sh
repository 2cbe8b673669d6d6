#!/usr/bin/env bash
# Runs one command-line test case against the real binary: cli_test.sh CASE RAYPC SHARED_DIR
set -uo pipefail
case_name=$1 raypc=$2 shared=$3
fixture=$shared/data/contest-layout
work=$(mktemp -d "${TMPDIR:-/tmp}/raypc-cli-$case_name.XXXXXX")
trap 'rm -rf "$work"' EXIT
failures=0

check() {  # check DESCRIPTION CONDITION...
  local what=$1; shift
  if "$@"; then echo "ok: $what"; else echo "FAIL: $what"; failures=$((failures + 1)); fi
}

# expect_error "FRAGMENT" ARGS...: exit status 1, exactly one line on stderr, naming FRAGMENT.
expect_error() {
  local fragment=$1; shift
  local err status
  err=$("$raypc" "$@" 2>&1 >/dev/null); status=$?
  if [[ $status -eq 0 ]]; then echo "FAIL: raypc $* exited 0"; failures=$((failures + 1)); return; fi
  if [[ $(printf '%s\n' "$err" | wc -l) -ne 1 ]]; then
    echo "FAIL: raypc $* printed more than one line:"; printf '%s\n' "$err"; failures=$((failures + 1)); return
  fi
  if [[ $err != *"$fragment"* ]]; then
    echo "FAIL: raypc $*: '$err' does not name '$fragment'"; failures=$((failures + 1)); return
  fi
  echo "ok: raypc $* -> $err"
}

preprocess_fixture() {
  "$raypc" preprocess "$fixture" -o "$work/ds" --quiet --sample-rows 2000 >/dev/null
}

case $case_name in
bad_options)
  preprocess_fixture
  expect_error "--grid" synth -o "$work/s" --grid 10x20
  expect_error "--grid" synth -o "$work/s" --grid 0x5x5
  expect_error "--steps" synth -o "$work/s" --steps 0
  expect_error "--format" synth -o "$work/s" --format hdf9
  expect_error "--map" preprocess "$fixture" -o "$work/x" --map temperature
  expect_error "--map" preprocess "$fixture" -o "$work/x" --map colour=T
  expect_error "--dt-myr" preprocess "$fixture" -o "$work/x" --dt-myr -2
  expect_error "unknown variable 'pressure'" probe "$work/ds" --lat 0 --lon 0 --r 5000 --var pressure
  expect_error "outside the mantle shell" probe "$work/ds" --lat 0 --lon 0 --r 7000
  expect_error "--lat" probe "$work/ds" --lat 95 --lon 0 --r 5000
  expect_error "step 9 out of range" probe "$work/ds" --time 9 --lat 0 --lon 0 --r 5000
  expect_error "no step at 3 Myr" probe "$work/ds" --time 3Myr --lat 0 --lon 0 --r 5000
  expect_error "--time" export "$work/ds" --time abc -o "$work/s.csv"
  expect_error "--what" export "$work/ds" --what volume -o "$work/s.csv"
  expect_error "level 5 out of range" probe "$work/ds" --lod 5 --lat 0 --lon 0 --r 5000
  check "no output written by failed commands" test ! -e "$work/s.csv" -a ! -e "$work/x/dataset.json"
  ;;
bad_inputs)
  expect_error "no such file" preprocess "$work/missing.nc" -o "$work/out"
  echo "not netCDF" > "$work/text.nc"
  expect_error "text.nc: not a netCDF file" info "$work/text.nc"
  head -c 1000000 "$fixture/spherical001.nc" > "$work/cut.nc"
  expect_error "cut.nc: truncated" preprocess "$work/cut.nc" -o "$work/out"
  check "no dataset after bad input" test ! -e "$work/out/dataset.json"
  expect_error "missing variable 'T'" info "$fixture/spherical001.nc" --map temperature=T
  mkdir -p "$work/empty"
  expect_error "no dataset.json" probe "$work/empty" --lat 0 --lon 0 --r 5000
  # A bad step in the middle: the run stops naming it; the finished steps stay, the dataset
  # says it is unfinished, and a rerun with the file repaired resumes.
  mkdir -p "$work/in"; cp "$fixture"/spherical00{1,2}.nc "$work/in/"; echo broken > "$work/in/spherical003.nc"
  head -c 2000000 "$fixture/spherical003.nc" > "$work/in/spherical003.nc"
  expect_error "spherical003.nc: truncated" preprocess "$work/in" -o "$work/ds"
  check "nothing written when a header is bad" test ! -e "$work/ds"
  # Damage that only shows in the data (a NaN) stops the run at that step.
  ncdump "$fixture/spherical003.nc" |
    awk 'done != 1 && after { sub(/[-0-9.e+]+/, "NaN"); done = 1 } /^ temperature =/ { after = 1 } { print }' > "$work/nan.cdl"
  ncgen -k nc6 -o "$work/in/spherical003.nc" "$work/nan.cdl"
  expect_error "spherical003.nc: temperature: 1 of" preprocess "$work/in" -o "$work/ds" --quiet
  expect_error "did not finish" info "$work/ds"
  cp "$fixture/spherical003.nc" "$work/in/"
  out=$("$raypc" preprocess "$work/in" -o "$work/ds" --quiet)
  check "rerun resumes ($out)" grep -q "1 written, 2 already done" <<<"$out"
  ;;
fixture_info_probe_export)
  preprocess_fixture
  info=$("$raypc" info "$work/ds" --json)
  check "info lists 3 steps" test "$(grep -c '"source": "spherical00' <<<"$info")" -eq 3
  check "info names radial velocity in cm/yr" grep -q '"cm/yr"' <<<"$info"
  # truth.json: the radial velocity is u0 = 5e-11 m/s = 0.15779 cm/yr everywhere.
  probe=$("$raypc" probe "$work/ds" --time 4Myr --lat 33 --lon 359.5 --r 5000 --var "radial velocity")
  value=$(tr -d ' \n' <<<"$probe" | grep -o '"radialvelocity":{"units":"cm/yr","value":[^}]*' | sed 's/.*"value"://')
  check "probe radial velocity '$value' == u0" awk -v v="$value" 'BEGIN { exit !(v != "" && (v - 0.157788) ^ 2 < 1e-8) }'
  "$raypc" export "$work/ds" --time 2 -o "$work/sample.csv" >/dev/null
  check "export writes 2000 rows + header" test "$(wc -l < "$work/sample.csv")" -eq 2001
  check "export header has units" grep -q '^x \[km\],.*temperature anomaly \[K\]' "$work/sample.csv"
  file_info=$("$raypc" info "$fixture/spherical001.nc")
  check "info on a file names its format" grep -q "64-bit offset" <<<"$file_info"
  ;;
synth_preprocess_kill_resume)
  "$raypc" synth -o "$work/nc" --steps 8 --grid 48x61x96 >/dev/null 2>&1
  check "synth wrote 8 files" test "$(ls "$work/nc" | grep -c '^spherical00[1-8].nc$')" -eq 8
  check "synth left no temporary files" test "$(ls -A "$work/nc" | wc -l)" -eq 8
  # Kill preprocessing once the first step is done.
  "$raypc" preprocess "$work/nc" -o "$work/ds" --quiet >/dev/null 2>&1 &
  pid=$!
  for _ in $(seq 1 600); do
    [[ -d $work/ds/steps/0001 ]] && break
    sleep 0.05
  done
  kill -9 "$pid" 2>/dev/null; wait "$pid" 2>/dev/null
  expect_error "did not finish" info "$work/ds"
  out=$("$raypc" preprocess "$work/nc" -o "$work/ds" --quiet)
  steps_line=$(grep " steps (" <<<"$out")
  check "resume skipped the finished steps ($steps_line)" grep -Eq "[0-9]+ written, [1-9][0-9]* already done" <<<"$steps_line"
  check "no temporary directories remain" test -z "$(find "$work/ds" -name '.*tmp*')"
  check "dataset opens with 8 steps" grep -q "steps: 8" <<<"$("$raypc" info "$work/ds")"
  ;;
stats_analytic_selection)
  preprocess_fixture
  # The fixture's radii are 3485 + i * 2886 / 40 km (41 shells); depth <= 660 km selects the
  # shells from the first radius >= 5711 km, whose dual cells start halfway below it. The radial
  # velocity is u0 = 0.15779 cm/yr everywhere, so a range around it keeps everything.
  expected=$(awk 'BEGIN { pi = atan2(0, -1); for (i = 0; i <= 40; i++) { r = 3485 + i * 2886 / 40;
      if (r >= 5711) { e = (prev + r) / 2; break } prev = r }
      printf "%.6e %.6f", 4 / 3 * pi * (6371^3 - e^3), 100 * (6371^3 - e^3) / (6371^3 - 3485^3) }')
  "$raypc" stats "$work/ds" --range "depth=0:660" --range "radial velocity=0.15:0.16" -o "$work/stats.csv" \
    --profile "$work/profile.csv" --quiet >/dev/null
  check "stats has a header and 3 steps" test "$(wc -l < "$work/stats.csv")" -eq 4
  read -r volume percent <<<"$expected"
  check "selected volume of every step is the analytic $volume km3 ($percent %)" awk -F, -v v="$volume" -v p="$percent" \
    'NR > 1 { n++; if (($3 - v)^2 > (1e-6 * v)^2 || ($4 - p)^2 > 1e-8) bad = 1 } END { exit bad || n != 3 }' "$work/stats.csv"
  check "profile: no selected volume below 660 km" awk -F, 'NR > 1 && $4 > 660 && $5 != 0 { bad = 1 } END { exit bad }' "$work/profile.csv"
  check "profile: shells above 660 km fully selected" awk -F, 'NR > 1 && $4 < 600 && ($7 - 100)^2 > 1e-6 { bad = 1 } END { exit bad }' "$work/profile.csv"
  "$raypc" stats "$work/ds" --range "radial velocity=0.2:0.3" -o "$work/none.csv" --quiet >/dev/null
  check "a range beside u0 selects nothing" awk -F, 'NR > 1 && $3 != 0 { bad = 1 } END { exit bad }' "$work/none.csv"
  expect_error "unknown variable or coordinate 'pressure'" stats "$work/ds" --range "pressure=0:1" -o "$work/x.csv"
  expect_error "min 3 is greater than max 1" stats "$work/ds" --range "depth=3:1" -o "$work/x.csv"
  check "no output after errors" test ! -e "$work/x.csv"
  ;;
*) echo "unknown case $case_name"; exit 2 ;;
esac

echo "$case_name: $failures failure(s)"
[[ $failures -eq 0 ]]
