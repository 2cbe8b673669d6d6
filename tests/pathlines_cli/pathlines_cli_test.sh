#!/usr/bin/env bash
# Usage: pathlines_cli_test.sh CASE RAYPC CONTEST_LAYOUT_DIR
# Preprocesses the contest fixture and exports its pathlines and critical points as CSV, VTK XML
# and legacy VTK. XML files are checked by xmllint (an independent parser) and, when pvpython is
# installed, opened by ParaView's readers with the expected counts. The fixture has two hot and two
# cold blobs (truth.json): the persistence cases check the diagram export and the seed rules
# (--cp-select, --cp-persistence, --cp-saddles) against them.
set -uo pipefail
case=$1 raypc=$2 fixture=$3
source "$(dirname "$0")/../lib/check.sh"
make_work pathlines-cli
expect_error() {  # expect_error PATTERN ARGS...: exit code 1 and PATTERN in the one-line message
  local pattern=$1; shift
  local out code
  out=$("$raypc" "$@" 2>&1); code=$?
  if [[ $code -eq 1 ]] && grep -q -- "$pattern" <<<"$out"; then
    echo "ok: error '$pattern' for: $*"
  else
    echo "FAIL: expected exit 1 with '$pattern' for: $*; got $code: $out"; failures=$((failures + 1))
  fi
}

"$raypc" preprocess "$fixture" -o "$work/ds" --sample-rows 500 --quiet >"$work/pp.log" 2>&1 \
  || { cat "$work/pp.log"; exit 1; }
seeds() {  # seeds CSV: the seed kinds of a critical-points export, one per line
  tail -n +2 "$1" | cut -d, -f1
}

case $case in
export_formats)
  check "preprocess reports pathlines" grep -q "pathlines of 3 steps" "$work/pp.log"
  for what in pathlines critical-points; do
    for ext in csv vtp vtk; do
      "$raypc" export "$work/ds" --time 0 --what $what -o "$work/$what.$ext" >"$work/out.log" 2>&1
      check "export $what .$ext" test -s "$work/$what.$ext"
    done
    check "$what.vtp is well-formed XML" xmllint --noout "$work/$what.vtp"
  done
  lines=$(grep -o 'NumberOfLines="[0-9]*"' "$work/pathlines.vtp" | grep -o '[0-9]*')
  points=$(grep -o 'NumberOfPoints="[0-9]*"' "$work/pathlines.vtp" | grep -o '[0-9]*')
  check "the CSV has one row per point" test "$(($(wc -l <"$work/pathlines.csv") - 1))" -eq "$points"
  check "the critical-points CSV has one row per line" test "$(($(wc -l <"$work/critical-points.csv") - 1))" -eq "$lines"
  check "the legacy file declares the points" grep -q "^POINTS $points float" "$work/pathlines.vtk"
  check "the legacy file declares the lines" grep -q "^LINES $lines $((lines + points))" "$work/pathlines.vtk"
  check "a maximum is among the seeds" grep -q "^maximum," "$work/critical-points.csv"
  check "a time given in Myr selects the step" "$raypc" export "$work/ds" --time 2Myr --what pathlines -o "$work/t.csv"
  if command -v pvpython >/dev/null; then
    cat >"$work/check.py" <<PY
from paraview.simple import *
for path, cells in (("$work/pathlines.vtp", $lines), ("$work/pathlines.vtk", $lines)):
    d = servermanager.Fetch(OpenDataFile(path))
    assert d.GetNumberOfPoints() == $points, (path, d.GetNumberOfPoints())
    assert d.GetNumberOfCells() == cells, (path, d.GetNumberOfCells())
    assert d.GetPointData().GetArray("age") is not None
d = servermanager.Fetch(OpenDataFile("$work/critical-points.vtp"))
assert d.GetNumberOfPoints() == $lines
PY
    check "ParaView reads the files" pvpython "$work/check.py"
  else
    echo "skip: pvpython not installed"
  fi
  ;;
bad_options)
  expect_error "--what" export "$work/ds" --what streamlines -o "$work/x.csv"
  expect_error "no known extension" export "$work/ds" --what pathlines -o "$work/x.txt"
  expect_error "--time" export "$work/ds" --what critical-points --time 7 -o "$work/x.csv"
  expect_error "--pathline-field" preprocess "$fixture" -o "$work/bad1" --pathline-field nope
  check "a refused run writes nothing" test ! -e "$work/bad1"
  expect_error "--pathline-steps" preprocess "$fixture" -o "$work/bad2" --pathline-steps 0
  expect_error "--cp-min-fraction" preprocess "$fixture" -o "$work/bad3" --cp-select value --cp-min-fraction 2
  expect_error "--cp-max-count" preprocess "$fixture" -o "$work/bad4" --cp-max-count 0
  check "a rerun with --no-pathlines succeeds" "$raypc" preprocess "$fixture" -o "$work/ds" --sample-rows 500 --no-pathlines --quiet
  check "--no-pathlines removes them" test ! -e "$work/ds/pathlines"
  expect_error "no-pathlines" export "$work/ds" --what pathlines -o "$work/x.vtp"
  ;;
persistence_export)
  check "export persistence" "$raypc" export "$work/ds" --time 0 --what persistence -o "$work/pd.csv"
  check "the header names both ends" grep -q '^kind,birth \[K\],death \[K\],persistence \[K\],birth kind,birth lat \[degrees_north\],.*,death z \[km\]$' "$work/pd.csv"
  check "18 columns in every row" awk -F, 'NF != 18 { exit 1 }' "$work/pd.csv"
  check "the first pair is the global one" awk -F, 'NR == 2 && $1 == "global" && $5 == "minimum" && $12 == "maximum" { ok = 1 } END { exit !ok }' "$work/pd.csv"
  check "persistence = death - birth >= 0, decreasing" awk -F, 'NR > 1 { d = $3 - $2 - $4; if (d > 1e-3 * ($4 + 1) || d < -1e-3 * ($4 + 1) || $4 < 0 || (NR > 2 && $4 > last + 1e-9)) exit 1; last = $4 }' "$work/pd.csv"
  check "minimum-saddle pairs start at a minimum, saddle-maximum pairs end at a maximum" awk -F, 'NR > 1 && (($1 == "minimum-saddle" && $5 != "minimum") || ($1 == "saddle-maximum" && $12 != "maximum")) { exit 1 }' "$work/pd.csv"
  # Four blobs: the global pair (400 K and -350 K blobs) and one pair each for the 300 K and -300 K
  # blobs stand out; everything else is far below (the anomaly is smooth).
  check "three pairs above 100 K" test "$(awk -F, 'NR > 1 && $4 > 100' "$work/pd.csv" | wc -l)" -eq 3
  check "one minimum-saddle and one saddle-maximum among them" test "$(awk -F, 'NR > 1 && $4 > 100 { print $1 }' "$work/pd.csv" | sort | tr '\n' ' ')" = "global minimum-saddle saddle-maximum "
  check "a time in Myr selects the step" "$raypc" export "$work/ds" --time 4Myr --what persistence -o "$work/pd4.csv"
  check "another variable" "$raypc" export "$work/ds" --time 0 --what persistence --var temperature -o "$work/pdt.csv"
  check "its units" grep -q '^kind,birth \[K\]' "$work/pdt.csv"
  ;;
seed_rules)
  "$raypc" export "$work/ds" --time 0 --what critical-points -o "$work/cp.csv" >/dev/null || exit 1
  check "default: one seed per blob" test "$(seeds "$work/cp.csv" | wc -l)" -eq 4
  check "default: two maxima and two minima" test "$(seeds "$work/cp.csv" | sort | uniq -c | tr -s ' ' | tr '\n' ';')" = " 2 maximum; 2 minimum;"
  check "the settings record the rule" grep -q '"rule": *"persistence"' "$work/ds/pathlines/0000/lines.json"
  "$raypc" preprocess "$fixture" -o "$work/ds" --sample-rows 500 --quiet --cp-saddles >/dev/null 2>&1 || exit 1
  "$raypc" export "$work/ds" --time 0 --what critical-points -o "$work/cps.csv" >/dev/null || exit 1
  check "--cp-saddles adds the two paired saddles" test "$(seeds "$work/cps.csv" | grep -c saddle)" -eq 2
  "$raypc" preprocess "$fixture" -o "$work/ds" --sample-rows 500 --quiet --cp-persistence 350 >/dev/null 2>&1 || exit 1
  "$raypc" export "$work/ds" --time 0 --what critical-points -o "$work/cp350.csv" >/dev/null || exit 1
  check "--cp-persistence 350 (K) keeps the global pair's two ends" test "$(seeds "$work/cp350.csv" | wc -l)" -eq 2
  "$raypc" preprocess "$fixture" -o "$work/ds" --sample-rows 500 --quiet --cp-persistence 100% >/dev/null 2>&1 || exit 1
  "$raypc" export "$work/ds" --time 0 --what critical-points -o "$work/cp100.csv" >/dev/null || exit 1
  check "--cp-persistence 100% keeps nothing" test "$(seeds "$work/cp100.csv" | wc -l)" -eq 0
  "$raypc" preprocess "$fixture" -o "$work/ds" --sample-rows 500 --quiet --cp-select value --cp-saddles --cp-min-fraction 0 >/dev/null 2>&1 || exit 1
  "$raypc" export "$work/ds" --time 0 --what critical-points -o "$work/cpv.csv" >/dev/null || exit 1
  check "the value rule is still there (with saddles)" grep -q '"rule": *"value"' "$work/ds/pathlines/0000/lines.json"
  # With no threshold it keeps nearly every critical point of the right sign (197 of 231 here).
  check "the value rule keeps many more" test "$(seeds "$work/cpv.csv" | wc -l)" -gt 100
  check "saddles among them" test "$(seeds "$work/cpv.csv" | grep -c saddle)" -gt 0
  ;;
seed_bad_options)
  expect_error "--cp-persistence" preprocess "$fixture" -o "$work/bad1" --cp-persistence abc
  check "a refused run writes nothing" test ! -e "$work/bad1"
  expect_error "--cp-persistence" preprocess "$fixture" -o "$work/bad2" --cp-persistence 150%
  expect_error "--cp-persistence" preprocess "$fixture" -o "$work/bad3" --cp-persistence -5
  expect_error "--cp-select" preprocess "$fixture" -o "$work/bad4" --cp-select top
  expect_error "--cp-min-abs: applies to seeds chosen by value" preprocess "$fixture" -o "$work/bad5" --cp-min-abs 10
  expect_error "--cp-persistence: applies to seeds chosen by persistence" preprocess "$fixture" -o "$work/bad6" --cp-select value --cp-persistence 5%
  check "refused runs write nothing" test ! -e "$work/bad5" -a ! -e "$work/bad6"
  "$raypc" preprocess "$fixture" -o "$work/ds" --sample-rows 500 --quiet --no-pathlines >/dev/null 2>&1 || exit 1
  expect_error "CSV only" export "$work/ds" --what persistence -o "$work/pd.vtp"
  expect_error "--var: no variable 'nope'" export "$work/ds" --what persistence --var nope -o "$work/pd.csv"
  expect_error "--time" export "$work/ds" --what persistence --time 9 -o "$work/pd.csv"
  check "nothing written" test ! -e "$work/pd.csv" -a ! -e "$work/pd.vtp"
  check "the persistence diagram needs no pathlines" "$raypc" export "$work/ds" --what persistence -o "$work/pd.csv"
  ;;
*)
  echo "unknown case $case"; exit 2 ;;
esac
[[ $failures -eq 0 ]] || { echo "$failures failure(s)"; exit 1; }
