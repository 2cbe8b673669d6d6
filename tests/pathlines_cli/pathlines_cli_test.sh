#!/usr/bin/env bash
# Usage: pathlines_cli_test.sh CASE RAYPC SHARED_DIR
# Preprocesses the contest fixture and exports its pathlines and critical points as CSV, VTK XML
# and legacy VTK. XML files are checked by xmllint (an independent parser) and, when pvpython is
# installed, opened by ParaView's readers with the expected counts.
set -uo pipefail
case=$1 raypc=$2 shared=$3
work=$(mktemp -d "${TMPDIR:-/tmp}/raypc-pathlines-cli.XXXXXX")
trap 'rm -rf "$work"' EXIT
failures=0
check() {  # check DESCRIPTION COMMAND...
  local what=$1; shift
  if "$@"; then echo "ok: $what"; else echo "FAIL: $what"; failures=$((failures + 1)); fi
}
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

"$raypc" preprocess "$shared/data/contest-layout" -o "$work/ds" --sample-rows 500 --quiet >"$work/pp.log" 2>&1 \
  || { cat "$work/pp.log"; exit 1; }

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
  expect_error "--pathline-field" preprocess "$shared/data/contest-layout" -o "$work/bad1" --pathline-field nope
  check "a refused run writes nothing" test ! -e "$work/bad1"
  expect_error "--pathline-steps" preprocess "$shared/data/contest-layout" -o "$work/bad2" --pathline-steps 0
  expect_error "--cp-min-fraction" preprocess "$shared/data/contest-layout" -o "$work/bad3" --cp-min-fraction 2
  expect_error "--cp-max-count" preprocess "$shared/data/contest-layout" -o "$work/bad4" --cp-max-count 0
  check "a rerun with --no-pathlines succeeds" "$raypc" preprocess "$shared/data/contest-layout" -o "$work/ds" --sample-rows 500 --no-pathlines --quiet
  check "--no-pathlines removes them" test ! -e "$work/ds/pathlines"
  expect_error "no-pathlines" export "$work/ds" --what pathlines -o "$work/x.vtp"
  ;;
*)
  echo "unknown case $case"; exit 2 ;;
esac
[[ $failures -eq 0 ]] || { echo "$failures failure(s)"; exit 1; }
