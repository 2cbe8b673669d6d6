#!/usr/bin/env bash
# Runs one command-line test case against the real binary: cli_test.sh CASE RAYPC CONTEST_LAYOUT_DIR
# (the contest-layout fixture, written at test time by tests/data).
set -uo pipefail
case_name=$1 raypc=$2 fixture=$3
source "$(dirname "$0")/../lib/check.sh"
make_work "cli-$case_name"

# The checks' Python is Debian's (RAYPC_PYTHON, set by ctest), whose netCDF4 and PIL they import: a
# python3 earlier on PATH (pyenv, a venv) lacks them.
python3() { "${RAYPC_PYTHON:-/usr/bin/python3}" "$@"; }

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


# check_emc_vs WHAT DATASET LAT LON DEPTH_KM: probe of vs there equals the EMC fixtures' formula
# (tests/data/emc-layout), within the quantisation error probe reports.
check_emc_vs() {
  local got
  got=$("$raypc" probe "$2" --lat "$3" --lon "$4" --r "$((6371 - $5))" --var vs)
  check "$1 at lat $3, lon $4, depth $5 km equals the file" python3 -c "
import json, math, sys
p = json.loads(sys.argv[1])['values']['vs']
lat, lon, d = map(float, sys.argv[2:5])
vs = 4.4 + 0.0007 * d + 0.1 * math.cos(math.radians(lat)) * math.cos(math.radians(lon - 30)) * (1 - d / 2891)
sys.exit(0 if abs(p['value'] - vs) <= p['quantisation_error_max'] + 1e-5 else 1)" "$got" "$3" "$4" "$5"
}
case $case_name in
bad_options)
  preprocess_fixture
  expect_error "--grid" synth -o "$work/s" --grid 10x20
  expect_error "--grid" synth -o "$work/s" --grid 0x5x5
  expect_error "--steps" synth -o "$work/s" --steps 0
  expect_error "--format" synth -o "$work/s" --format hdf9
  expect_error "--map" preprocess "$fixture" -o "$work/x" --map temperature
  expect_error "missing variable 'T' (mapped from 'colour')" preprocess "$fixture" -o "$work/x" --map colour=T
  expect_error "--map: 'depth' is a coordinate's name" preprocess "$fixture" -o "$work/x" --map depth=temperature
  expect_error "--map: 'radial velocity' is derived from the velocity" preprocess "$fixture" -o "$work/x" \
    --map "radial velocity=vx"
  expect_error "--map: 'temperature' is read as both 'a' and 'b'" preprocess "$fixture" -o "$work/x" \
    --map a=temperature --map b=temperature
  expect_error "--dt-myr" preprocess "$fixture" -o "$work/x" --dt-myr -2
  expect_error "unknown variable 'pressure'" probe "$work/ds" --lat 0 --lon 0 --r 5000 --var pressure
  expect_error "outside the mantle shell" probe "$work/ds" --lat 0 --lon 0 --r 7000
  expect_error "--lat" probe "$work/ds" --lat 95 --lon 0 --r 5000
  expect_error "--time: 9 out of range 0..2" probe "$work/ds" --time 9 --lat 0 --lon 0 --r 5000
  expect_error "no step at 3 Myr" probe "$work/ds" --time 3Myr --lat 0 --lon 0 --r 5000
  expect_error "--time" export "$work/ds" --time abc -o "$work/s.csv"
  expect_error "--what" export "$work/ds" --what volume -o "$work/s.csv"
  expect_error "--lod: 5 out of range 0..2" probe "$work/ds" --lod 5 --lat 0 --lon 0 --r 5000
  expect_error "--dataset DIR" serve "$fixture/spherical001.nc" "$fixture/spherical002.nc" --dataset /proc/raypc-x --port 0
  expect_error "missing.nc: no such file" serve "$work/missing.nc" --port 0
  expect_error "--dataset: only for netCDF inputs" serve "$work/ds" --dataset "$work/y" --port 0
  check "no output written by failed commands" test ! -e "$work/s.csv" -a ! -e "$work/x/dataset.json" -a ! -e "$work/y"
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
  # Damage that only shows in the data (a variable with no value in the step: NaN everywhere) stops
  # the run at that step.
  cp "$fixture/spherical003.nc" "$work/in/spherical003.nc"
  python3 -c "
import netCDF4, numpy, sys
with netCDF4.Dataset(sys.argv[1], 'a') as nc:
    nc.variables['temperature'][:] = numpy.nan" "$work/in/spherical003.nc"
  expect_error "spherical003.nc: temperature: every value of the step is missing" preprocess "$work/in" -o "$work/ds" --quiet
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
  value=$(tr -d ' \n' <<<"$probe" | grep -o '"radialvelocity":{[^}]*' | sed 's/.*"value"://')
  bound=$(tr -d ' \n' <<<"$probe" | grep -o '"radialvelocity":{[^}]*' | sed 's/.*"quantisation_error_max":\([^,]*\),.*/\1/')
  check "probe radial velocity '$value' == u0" awk -v v="$value" 'BEGIN { exit !(v != "" && (v - 0.157788) ^ 2 < 1e-8) }'
  # A field constant up to float32 rounding has bricks of (almost) no range: a bound of (almost) 0.
  check "probe reports the quantisation bound '$bound' (about 0 for a constant field)" awk -v b="$bound" 'BEGIN { exit !(b != "" && b + 0 < 1e-9) }'
  # Every variable probed in a u16 and a float32 dataset of the fixture: within the bound probe prints.
  "$raypc" preprocess "$fixture" -o "$work/ds32" --quiet --sample-rows 2000 --no-pathlines --encoding float32 >/dev/null
  "$raypc" probe "$work/ds" --time 2 --lat 47.5 --lon 121 --r 4100 >"$work/p16.json"
  "$raypc" probe "$work/ds32" --time 2 --lat 47.5 --lon 121 --r 4100 >"$work/p32.json"
  check "u16 probe values are within their quantisation bound of float32's" python3 - "$work/p16.json" "$work/p32.json" <<'PY'
import json, sys
a, b = (json.load(open(f))["values"] for f in sys.argv[1:3])
# The file's 8, the velocity's 2 and 3 shell anomalies computed when read (their bounds: the base's
# at the point and on its shell).
assert len(a) == 13 and a.keys() == b.keys()
assert sum(a[k]["quantisation_error_max"] > 0 for k in a) >= 8
for k in a:
    assert b[k]["quantisation_error_max"] == 0, k
    d = abs(a[k]["value"] - b[k]["value"])
    assert d <= a[k]["quantisation_error_max"] * (1 + 1e-6) + 1e-6 * abs(b[k]["value"]), (k, d, a[k])
PY
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
  # A variable's mean per depth (--profile-var): the temperature less its anomaly is the truth's
  # radial profile, 300 + 3700 (6371 - r) / 2886 K, in every shell's mean (u16 values: 0.1 K); in the
  # depth range every shell is selected whole (selected mean = shell mean), outside none (empty).
  for var in temperature "temperature anomaly"; do
    "$raypc" stats "$work/ds" --range "depth=500:1500" -o "$work/m.csv" --profile "$work/m-$var.csv" \
      --profile-var "$var" --quiet >/dev/null
  done
  check "--profile-var: shell means of T - T' are the truth's profile; selected = shell within the range, empty outside" \
    python3 - "$work/m-temperature.csv" "$work/m-temperature anomaly.csv" <<'PY'
import csv, sys
t, a = (list(csv.DictReader(open(f))) for f in sys.argv[1:])
worst, ok = 0.0, len(t) == len(a) == 3 * 41
for rt, ra in zip(t, a):
    d = float(rt["depth_km"])
    worst = max(worst, abs(float(rt["temperature shell mean [K]"]) - float(ra["temperature anomaly shell mean [K]"]) - (300 + 3700 * d / 2886)))
    sel = rt["temperature selected mean [K]"]
    if float(rt["selected_volume_km3"]) > 0:
        ok &= float(rt["selected_percent_of_shell"]) > 99.999 and abs(float(sel) - float(rt["temperature shell mean [K]"])) < 1e-6 * 4000
    else:
        ok &= sel == ""
print("largest |T - T' - profile| over the shells:", worst, "K")
sys.exit(not (ok and worst < 0.1))
PY
  # The time-depth picture (--hovmoller) of depth <= 660 km: every step's shells above 660 km at the
  # top of the colours (100 %), those below at the bottom (0 %); rows show the nearest radius, so the
  # top colour reaches down to half way between the radii at 659.7 and 731.8 km: 695.7 of 2886 km.
  # The 660 km mark (a dash on a dark casing) covers the rows around that edge, so the edge is taken
  # half way between the last top-coloured and the first bottom-coloured row: between 660 and 695.7 km
  # (within a pixel and a half), with no more than the casing's rows between them.
  "$raypc" stats "$work/ds" --range "depth=0:660" -o "$work/h.csv" --hovmoller "$work/hov.png" --size 640x400 --quiet >/dev/null
  check "--hovmoller: the share is 100 % above 660 km and 0 below, in the picture's rows" python3 - "$work/hov.png" <<'PY'
import sys
from PIL import Image
im = Image.open(sys.argv[1]).convert("RGB")
assert im.size == (640, 400), im.size
near = lambda c, ref: sum((a - b) ** 2 for a, b in zip(c, ref)) < 30 ** 2
top, bottom = (253, 231, 37), (68, 1, 84)  # viridis at 1 and 0
for x in (200, 320, 440):  # three columns: the three steps
    col = [im.getpixel((x, y)) for y in range(im.height)]
    ys_top = [y for y, c in enumerate(col) if near(c, top)]
    ys_bottom = [y for y, c in enumerate(col) if near(c, bottom)]
    span = max(ys_bottom) - min(ys_top) + 1
    km_per_px = 2886 / span
    gap = min(ys_bottom) - max(ys_top) - 1
    edge_km = ((max(ys_top) + min(ys_bottom)) / 2 - min(ys_top) + 0.5) * km_per_px
    print(f"column {x}: top colour down to {edge_km:.0f} km ({gap} rows under the mark; expected 660-695.7 km)")
    assert 0 <= gap <= 12 and 660 - 1.5 * km_per_px <= edge_km <= 695.7 + 1.5 * km_per_px
PY
  "$raypc" stats "$work/ds" --range "depth=500:1500" -o "$work/h.csv" --hovmoller "$work/hov-t.png" --profile-var temperature \
    --hovmoller-of shell-mean --depth 660 --quiet >/dev/null
  check "--hovmoller-of shell-mean: the picture is written" test -s "$work/hov-t.png"
  expect_error "--hovmoller-of 'mean': expected share, selected-mean or shell-mean" stats "$work/ds" -o "$work/x.csv" --hovmoller "$work/x.png" --hovmoller-of mean
  expect_error "--hovmoller-of selected-mean: needs --profile-var" stats "$work/ds" -o "$work/x.csv" --hovmoller "$work/x.png" --hovmoller-of selected-mean
  expect_error "--depth 7000: expected a depth in km between 0 and 6371" stats "$work/ds" -o "$work/x.csv" --hovmoller "$work/x.png" --depth 7000
  expect_error "--hovmoller-of, --depth: need --hovmoller" stats "$work/ds" -o "$work/x.csv" --depth 660
  expect_error "time-depth picture: 40x30 pixels have no room for the plot" stats "$work/ds" -o "$work/x.csv" --hovmoller "$work/x.png" --size 40x30
  expect_error "--size '0x10': expected WIDTHxHEIGHT" stats "$work/ds" -o "$work/x.csv" --hovmoller "$work/x.png" --size 0x10
  check "no picture after errors" test ! -e "$work/x.png"
  expect_error "--profile-var: unknown variable 'pressure'" stats "$work/ds" --profile "$work/x.csv" --profile-var pressure -o "$work/x.csv"
  expect_error "--profile-var: needs --profile" stats "$work/ds" --profile-var temperature -o "$work/x.csv"
  "$raypc" stats "$work/ds" --range "radial velocity=0.2:0.3" -o "$work/none.csv" --quiet >/dev/null
  check "a range beside u0 selects nothing" awk -F, 'NR > 1 && $3 != 0 { bad = 1 } END { exit bad }' "$work/none.csv"
  expect_error "unknown variable or coordinate 'pressure'" stats "$work/ds" --range "pressure=0:1" -o "$work/x.csv"
  expect_error "min 3 is greater than max 1" stats "$work/ds" --range "depth=3:1" -o "$work/x.csv"
  check "no output after errors" test ! -e "$work/x.csv"
  ;;
features)
  # raypc features: the connected regions of a selection, each measured.
  preprocess_fixture
  vol() { "$raypc" stats "$work/ds" --quiet -o "$work/v.csv" "$@" >/dev/null && awk -F, 'NR > 1 { print $3 }' "$work/v.csv"; }
  "$raypc" features "$work/ds" --range depth=0:660 -o "$work/shell.csv" --quiet >/dev/null
  check "a shell is one feature a step" test "$(awk -F, 'NR > 1' "$work/shell.csv" | wc -l)" -eq 3
  check "  with the volume raypc stats gives" \
    awk -F, -v v="$(vol --range depth=0:660 | head -1)" 'NR == 2 { exit ($5 - v)^2 > (1e-6 * v)^2 }' "$work/shell.csv"
  # Two polar caps: each joined around its pole, apart from the other: two features a step, whose
  # volumes add up to the selection's.
  "$raypc" features "$work/ds" --range depth=0:660 --range lat=-90:-60 --range lat=60:90 -o "$work/caps.csv" --quiet >/dev/null
  check "two polar caps are two features a step" test "$(awk -F, 'NR > 1 && $1 == 0' "$work/caps.csv" | wc -l)" -eq 2
  check "  one in each hemisphere" awk -F, 'NR > 1 && $1 == 0 { if ($10 > 60) n++; if ($10 < -60) s++ } END { exit !(n == 1 && s == 1) }' "$work/caps.csv"
  check "  adding up to the selected volume" awk -F, -v v="$(vol --range depth=0:660 --range lat=-90:-60 --range lat=60:90 | head -1)" \
    'NR > 1 && $1 == 0 { t += $5 } END { exit (t - v)^2 > (1e-6 * v)^2 }' "$work/caps.csv"
  check "  the header names units and bands" grep -q "temperature mean \[K\].*percent_within_50km_of_660km" "$work/caps.csv"
  # Followed through the 3 steps (the fixture's flow is slow: each cap stays itself): two tracks of
  # three steps each, no events.
  "$raypc" features "$work/ds" --range depth=0:660 --range lat=-90:-60 --range lat=60:90 -o "$work/caps2.csv" \
    --tracks "$work/tracks.csv" --events "$work/events.csv" --quiet >/dev/null
  check "the caps are two tracks of 3 steps" test "$(awk -F, 'NR > 1 { n[$1]++ } END { for (t in n) if (n[t] == 3) k++; print k }' "$work/tracks.csv")" -eq 2
  check "  with no events" test "$(wc -l < "$work/events.csv")" -eq 1
  check "  and the same features as without tracking" cmp -s "$work/caps.csv" "$work/caps2.csv"
  # Their mean depth (the shell 0-660 km, weighted by volume: about 310 km) stays in a band of
  # 250-350 km for the whole series: a stall of every step, still there at the end.
  "$raypc" features "$work/ds" --range depth=0:660 --range lat=-90:-60 --range lat=60:90 -o "$work/caps3.csv" \
    --depth 300 --band-half-width 50 --stalls "$work/stalls.csv" --quiet >/dev/null
  check "each cap stalls at 300 km from step 0 to 2" \
    awk -F, 'NR > 1 { n++; if ($2 != 300 || $3 != 0 || $4 != 2 || $7 != "") bad = 1 } END { exit bad || n != 2 }' "$work/stalls.csv"
  # The same from a state whose `features` (version 10) hold the depth and band: the same files;
  # an option given on the command line overrides the state's; a level the dataset lacks names the key.
  printf '%s' '{"version": 10, "brushes": [{"name": "depth", "min": 0, "max": 660}, {"name": "lat", "min": -90, "max": -60},
    {"name": "lat", "min": 60, "max": 90}], "features": {"depthsKm": [300], "bandHalfWidthKm": 50}}' > "$work/caps.json"
  "$raypc" features "$work/ds" --state "$work/caps.json" -o "$work/caps4.csv" --stalls "$work/stalls4.csv" --quiet >/dev/null
  check "the state's feature settings give the same features and stalls as the options" \
    bash -c "cmp -s '$work/caps3.csv' '$work/caps4.csv' && cmp -s '$work/stalls.csv' '$work/stalls4.csv'"
  "$raypc" features "$work/ds" --state "$work/caps.json" --depth 660 -o "$work/caps5.csv" --quiet >/dev/null
  check "  --depth overrides the state's depths" grep -q "percent_within_50km_of_660km" "$work/caps5.csv"
  printf '%s' '{"version": 10, "brushes": [{"name": "depth", "min": 0, "max": 660}], "features": {"level": 1}}' > "$work/lod.json"
  "$raypc" features "$work/ds" --state "$work/lod.json" -o "$work/lod-state.csv" --quiet >/dev/null
  "$raypc" features "$work/ds" --range depth=0:660 --lod 1 -o "$work/lod-option.csv" --quiet >/dev/null
  check "  features.level is --lod's" cmp -s "$work/lod-state.csv" "$work/lod-option.csv"
  check "  and not level 0's" bash -c "! cmp -s '$work/lod-state.csv' '$work/shell.csv'"
  "$raypc" features "$work/ds" --range "radial velocity=0.2:0.3" -o "$work/none.csv" --quiet > "$work/none.out"
  check "an empty selection writes the header alone" test "$(wc -l < "$work/none.csv")" -eq 1
  check "  and says 0 features" grep -q "0 features in 3 steps" "$work/none.out"
  expect_error "no selection" features "$work/ds" -o "$work/x.csv"
  expect_error "--min-volume" features "$work/ds" --range depth=0:660 --min-volume -1 -o "$work/x.csv"
  expect_error "unknown variable or coordinate 'pressure'" features "$work/ds" --range pressure=0:1 -o "$work/x.csv"
  check "no output after errors" test ! -e "$work/x.csv"
  ;;
flux)
  # raypc flux: the fixture's radial velocity is u0 = 0.15779 cm/yr everywhere (its
  # truth.json), so the flux up across a shell of radius r is 4 pi r^2 u0 (km^3/yr with 1e-5 km/cm).
  preprocess_fixture
  "$raypc" flux "$work/ds" --depth 660 --depth 1600 --range lat=0:90 -o "$work/flux.csv" --quiet >/dev/null
  check "a row per step and depth" test "$(awk -F, 'NR > 1' "$work/flux.csv" | wc -l)" -eq 6
  check "up is 4 pi r^2 u0, down 0, at both depths" awk -F, 'NR > 1 { pi = atan2(0, -1); up = 4 * pi * $4^2 * 0.15779e-5;
      if (($6 - up)^2 > (1e-3 * up)^2 || $5 != 0 || ($7 - $6)^2 > (1e-9 * up)^2) bad = 1 } END { exit bad }' "$work/flux.csv"
  check "the selection (the northern half) carries half" \
    awk -F, 'NR > 1 { if (($9 - $6 / 2)^2 > (1e-3 * $6)^2 || ($10 - 50)^2 > 0.5) bad = 1 } END { exit bad }' "$work/flux.csv"
  check "a steady flow has no avalanche" awk -F, 'NR > 1 && $11 != 0 { bad = 1 } END { exit bad }' "$work/flux.csv"
  # The advective heat flux (--heat-flux; its analytic value for a uniform flow and anomaly is
  # ShellFlux.AdvectiveHeatFlux…): the northern and southern selections add up to the whole shell,
  # and twice the density gives twice the flux.
  for half in 0:90 -90:0; do
    "$raypc" flux "$work/ds" --depth 660 --depth 1600 --range "lat=$half" --heat-flux -o "$work/heat$half.csv" --quiet >/dev/null
  done
  "$raypc" flux "$work/ds" --depth 660 --depth 1600 --heat-flux --density 6600 -o "$work/heat2.csv" --quiet >/dev/null
  check "--heat-flux: columns heat_flux_w and selected_heat_flux_w" \
    awk -F, 'NR == 1 { exit !($12 == "heat_flux_w" && $13 == "selected_heat_flux_w") }' "$work/heat0:90.csv"
  check "--heat-flux: north + south = the whole shell; twice the density, twice the flux" python3 - "$work" <<'PY'
import csv, sys
w = sys.argv[1]
north, south, double = (list(csv.DictReader(open(f"{w}/{n}.csv"))) for n in ("heat0:90", "heat-90:0", "heat2"))
ok = len(north) == len(south) == len(double) == 6
for n, s, d in zip(north, south, double):
    whole = float(n["heat_flux_w"])
    parts = float(n["selected_heat_flux_w"]) + float(s["selected_heat_flux_w"])
    print(f"step {n['step']} depth {n['depth_km']}: Q = {whole:.4e} W, north + south = {parts:.4e} W, 2 rho: {float(d['heat_flux_w']):.4e} W")
    ok &= whole != 0 and abs(parts - whole) <= 1e-6 * abs(whole) + 1e3 and abs(float(d["heat_flux_w"]) - 2 * whole) <= 1e-5 * abs(whole)
sys.exit(not ok)
PY
  expect_error "--density: -1 kg/m3 is not positive" flux "$work/ds" --heat-flux --density -1 -o "$work/x.csv"
  expect_error "--density, --heat-capacity: need --heat-flux" flux "$work/ds" --heat-capacity 1000 -o "$work/x.csv"
  expect_error "outside the grid's radii" flux "$work/ds" --depth 3000 -o "$work/x.csv"
  expect_error "--sigmas" flux "$work/ds" --sigmas -1 -o "$work/x.csv"
  check "no output after errors" test ! -e "$work/x.csv"
  ;;
maps_sections)
  # Maps and sections (docs/maps.md) on the analytic fixture (its truth.json), in float32.
  "$raypc" preprocess "$fixture" -o "$work/ds" --quiet --sample-rows 2000 --encoding float32 >/dev/null
  "$raypc" map "$work/ds" --time 1 --depth 1000 --var temperature --size 600x360 -o "$work/t.png" \
    --netcdf "$work/t.nc" --grid-step 2 >/dev/null
  "$raypc" map "$work/ds" --time 1 --depth 1000 --var "temperature anomaly" --size 600x360 -o "$work/a.png" \
    --netcdf "$work/a.nc" --grid-step 2 --flow --contours=-100,100 --reference coastlines --reference graticule >/dev/null
  "$raypc" section "$work/ds" --time 0 --var "temperature anomaly" --from=-20,40 --to 60,40 --size 600x360 \
    -o "$work/s.png" --netcdf "$work/s.nc" --grid-step 1 --depth-step 20 --flow >/dev/null
  check "the pictures are 600x360 PNGs" python3 -c "
from PIL import Image
import sys
sys.exit(any(Image.open('$work/' + f).size != (600, 360) for f in ('t.png', 'a.png', 's.png')))"
  # The temperature less its anomaly is 300 + 3700 (6371 - r) / 2886 K (truth.json): at 1000 km the
  # same everywhere, poles (the 89° rows lie in the grid's pole caps) and the lon seam (359°) included.
  check "netCDF map: CF coordinates, and T - T' is the truth's radial profile at every point" python3 -c "
import netCDF4, numpy as np, sys
t, a = netCDF4.Dataset('$work/t.nc'), netCDF4.Dataset('$work/a.nc')
lat, lon, d = t['lat'], t['lon'], t['depth']
ok = lat.units == 'degrees_north' and lon.units == 'degrees_east' and lat.standard_name == 'latitude'
ok &= d.units == 'km' and d.positive == 'down' and float(d[...]) == 1000 and t.Conventions == 'CF-1.8'
ok &= lat.shape == (90,) and lon.shape == (180,) and lat[0] == -89 and lat[-1] == 89 and lon[0] == 1 and lon[-1] == 359
T, A = t['temperature'], a['temperature_anomaly']
ok &= T.units == 'K' and A.long_name == 'temperature anomaly' and T.dimensions == ('lat', 'lon')
diff = np.asarray(T[:], float) - np.asarray(A[:], float) - (300 + 3700 * 1000 / 2886)
print('largest |T - T\' - profile|:', np.abs(diff).max(), 'K')
sys.exit(not (ok and np.abs(diff).max() < 0.01))"
  # The section along the meridian 40°E from 20°S to 60°N meets the fixture's first blob (amplitude
  # 400 K, at 20°N 40°E, r 4300 km, i.e. 2071 km deep, at step 0) 40° along, at its depth.
  check "netCDF section: the blob's peak at 40 degrees along and 2071 km deep" python3 -c "
import netCDF4, numpy as np, sys
s = netCDF4.Dataset('$work/s.nc')
v = np.asarray(s['temperature_anomaly'][:], float)
i, j = np.unravel_index(np.argmax(v), v.shape)
# On 5-degree cells the interpolated peak sits on a grid row (17.5 N): the centre is the centroid of
# the values above half the peak, along the peak's depth and down the peak's column.
row, col = np.clip(v[i] - v[i, j] / 2, 0, None), np.clip(v[:, j] - v[i, j] / 2, 0, None)
along = float((row * s['distance_deg'][:]).sum() / row.sum())
depth = float((col * s['depth'][:]).sum() / col.sum())
lat = float(np.interp(along, s['distance_deg'][:], s['lat'][:]))
print('peak', v[i, j], 'K; centre', along, 'deg along (lat', lat, '),', depth, 'km deep')
ok = s['depth'].positive == 'down' and s['distance'].units == 'km' and abs(float(s['distance'][-1]) - 80 * np.pi / 180 * 6371) < 1
sys.exit(not (ok and abs(along - 40) <= 1 and abs(depth - 2071) <= 60 and abs(lat - 20) <= 1 and v[i, j] > 250))"
  check "GMT reads the map as a geographic grid, 0..360 x -90..90 at 2 degrees" bash -c "
    gmt grdinfo '$work/t.nc' | grep -q 'Geographic grid' &&
    gmt grdinfo -C '$work/t.nc' | awk '{ exit !(\$2 == 0 && \$3 == 360 && \$4 == -90 && \$5 == 90 && \$8 == 2 && \$10 == 180 && \$11 == 90) }'"
  # One description: the state's map drawn by render --view map is raypc map's picture.
  printf '%s' '{"version": 9, "color": {"variable": "temperature anomaly"}, "map": {"depthKm": 660,
    "projection": "hammer", "centralMeridianDeg": -100, "contours": [0]}, "section": {"from": {"latDeg": 0, "lonDeg": 0},
    "to": {"latDeg": 45, "lonDeg": 90}}}' > "$work/state.json"
  "$raypc" map "$work/ds" --state "$work/state.json" --size 400x240 -o "$work/m1.png" >/dev/null
  "$raypc" render "$work/ds" --state "$work/state.json" --size 400x240 --view map -o "$work/m2.png" >/dev/null
  "$raypc" section "$work/ds" --state "$work/state.json" --size 400x240 -o "$work/s1.png" >/dev/null
  "$raypc" render "$work/ds" --state "$work/state.json" --size 400x240 --view section -o "$work/s2.png" >/dev/null
  check "render --view map draws raypc map's picture" cmp -s "$work/m1.png" "$work/m2.png"
  check "render --view section draws raypc section's picture" cmp -s "$work/s1.png" "$work/s2.png"
  "$raypc" map "$work/ds" --state "$work/state.json" --size 400x240 --projection orthographic -o "$work/m3.png" >/dev/null
  check "--projection changes the state's" bash -c "! cmp -s '$work/m1.png' '$work/m3.png'"
  # A section by azimuth and length: its far end (the netCDF's last column) where spherical
  # trigonometry puts it, and its picture that of the same section given by --to.
  "$raypc" section "$work/ds" --from=-20,40 --azimuth 30 --length 50 --size 400x240 -o "$work/z1.png" \
    --netcdf "$work/z.nc" --grid-step 1 --depth-step 100 >/dev/null
  check "--azimuth 30 --length 50 from 20S 40E ends where the destination formula says" python3 -c "
import netCDF4, numpy as np, sys
s = netCDF4.Dataset('$work/z.nc')
r = np.pi / 180; la, lo, az, d = -20 * r, 40 * r, 30 * r, 50 * r
lat2 = np.arcsin(np.sin(la) * np.cos(d) + np.cos(la) * np.sin(d) * np.cos(az))
lon2 = lo + np.arctan2(np.sin(az) * np.sin(d) * np.cos(la), np.cos(d) - np.sin(la) * np.sin(lat2))
print('end', float(s['lat'][-1]), float(s['lon'][-1]), 'expected', lat2 / r, lon2 / r, 'length', float(s['distance_deg'][-1]))
sys.exit(not (abs(s['lat'][-1] - lat2 / r) < 1e-3 and abs((s['lon'][-1] - lon2 / r + 180) % 360 - 180) < 1e-3
              and abs(s['distance_deg'][-1] - 50) < 1e-3))"
  to=$(python3 -c "
import netCDF4; s = netCDF4.Dataset('$work/z.nc'); print('%.6f,%.6f' % (s['lat'][-1], s['lon'][-1]))")
  "$raypc" section "$work/ds" --from=-20,40 --to "$to" --size 400x240 -o "$work/z2.png" >/dev/null
  check "the same picture as --to $to" cmp -s "$work/z1.png" "$work/z2.png"
  expect_error "--azimuth and --length: give both" section "$work/ds" --from 10,20 --azimuth 30 -o "$work/x.png"
  expect_error "--to and --azimuth" section "$work/ds" --from 10,20 --to 0,0 --azimuth 30 --length 10 -o "$work/x.png"
  expect_error "--length 200" section "$work/ds" --from 10,20 --azimuth 30 --length 200 -o "$work/x.png"
  expect_error "less than 0.01° apart" section "$work/ds" --from 10,20 --to 10,20 -o "$work/x.png"
  expect_error "antipodal" section "$work/ds" --from 30,20 --to=-30,200 -o "$work/x.png"
  expect_error "--from '95,0'" section "$work/ds" --from 95,0 --to 0,0 -o "$work/x.png"
  expect_error "unknown map projection 'mercator'" map "$work/ds" --projection mercator -o "$work/x.png"
  expect_error "outside the grid's depths" map "$work/ds" --depth 3000 -o "$work/x.png"
  expect_error "--grid-step 0.7" map "$work/ds" --netcdf "$work/x.nc" --grid-step 0.7 -o "$work/x.png"
  expect_error "--view 'globe'" render "$work/ds" --view globe -o "$work/x.png"
  expect_error "only for --view 3d" render "$work/ds" --view map --depth "$work/x.pfm" -o "$work/x.png"
  printf '%s' '{"version": 8, "map": {"depthKm": 660}}' > "$work/old.json"
  expect_error "map: needs version 9" map "$work/ds" --state "$work/old.json" -o "$work/x.png"
  check "no output after errors" test ! -e "$work/x.png" -a ! -e "$work/x.nc" -a ! -e "$work/x.pfm"
  ;;
multi_range)
  # Several ranges on one axis (a name given twice) select their union, in raypc stats and render,
  # from --range and from a state alike; --range replaces the state's ranges of its name.
  preprocess_fixture
  vol() { "$raypc" stats "$work/ds" --quiet -o "$work/v.csv" "$@" >/dev/null && awk -F, 'NR > 1 { print $3 }' "$work/v.csv"; }
  a=$(vol --range depth=0:660) b=$(vol --range depth=1500:2000) ab=$(vol --range depth=0:660 --range depth=1500:2000)
  check "disjoint depth ranges: the union's volume is the sum, every step ($ab)" \
    awk -v a="$a" -v b="$b" -v ab="$ab" 'BEGIN { na = split(a, A); split(b, B); split(ab, C);
      for (i = 1; i <= na; i++) if (A[i] <= 0 || B[i] <= 0 || (C[i] - A[i] - B[i])^2 > (1e-9 * C[i])^2) exit 1; exit na != 3 }'
  check "overlapping ranges select the merged range" test "$(vol --range depth=0:660 --range depth=500:1200)" = "$(vol --range depth=0:1200)"
  printf '%s' '{"version": 4, "brushes": [{"name": "depth", "min": 0, "max": 660}, {"name": "lat", "min": -90, "max": 90},
    {"name": "depth", "min": 1500, "max": 2000}]}' > "$work/multi.json"
  check "a state with two depth ranges gives what two --range do" test "$(vol --state "$work/multi.json")" = "$ab"
  check "--range depth replaces both of the state's depth ranges" \
    test "$(vol --state "$work/multi.json" --range depth=1500:2000)" = "$b"
  "$raypc" render "$work/ds" -o "$work/touching.png" --size 64x64 --passes 1 --range depth=0:660 --range depth=660:1500 >/dev/null
  "$raypc" render "$work/ds" -o "$work/merged.png" --size 64x64 --passes 1 --range depth=0:1500 >/dev/null
  "$raypc" render "$work/ds" -o "$work/lower.png" --size 64x64 --passes 1 --range depth=660:1500 >/dev/null
  check "render: touching ranges draw the merged range's picture" cmp -s "$work/touching.png" "$work/merged.png"
  check "render: the upper range adds to the picture" bash -c "! cmp -s '$work/lower.png' '$work/merged.png'"
  "$raypc" render "$work/ds" -o "$work/state.png" --size 64x64 --passes 1 --state "$work/multi.json" >/dev/null
  # The same document without brushes, so that only the ranges differ (without --state, render
  # starts from the UI's first view instead of the document's defaults).
  printf '%s' '{"version": 4, "brushes": [{"name": "lat", "min": -90, "max": 90}]}' > "$work/lat-only.json"
  "$raypc" render "$work/ds" -o "$work/ranges.png" --size 64x64 --passes 1 --state "$work/lat-only.json" \
    --range depth=0:660 --range depth=1500:2000 >/dev/null
  check "render: the state's two ranges draw what two --range do" cmp -s "$work/state.png" "$work/ranges.png"
  sed 's/"version": 4/"version": 3/' "$work/multi.json" > "$work/v3.json"
  expect_error "v3.json: brushes[2]: a second range on 'depth' needs version 4" stats "$work/ds" --state "$work/v3.json" -o "$work/x.csv"
  printf '%s' '{"version": 4, "brushes": [{"name": "depth", "min": 0, "max": 660}, {"name": "depth", "min": 900, "max": 800}]}' > "$work/bad.json"
  expect_error "bad.json: brushes[1].min: min 900 is greater than max 800" render "$work/ds" --state "$work/bad.json" -o "$work/x.png"
  check "no output after errors" test ! -e "$work/x.csv" -a ! -e "$work/x.png"
  ;;
finite_overflow)
  # One vx = 1e30 (finite) makes the velocity magnitude overflow float32; it crashed
  # in the histogram. The first value in the file is at lat 87.5 (the file descends), r 3485, lon 0.
  mkdir -p "$work/in"
  ncdump "$fixture/spherical001.nc" |
    awk 'done != 1 && after { sub(/[-0-9.e+]+/, "1e30"); done = 1 } /^ vx =/ { after = 1 } { print }' > "$work/big.cdl"
  ncgen -k nc6 -o "$work/in/big.nc" "$work/big.cdl"
  expect_error "big.nc: velocity magnitude: inf (beyond float32) at lat 87.5°, r 3485 km, lon 0° (point 35, 0, 0 of lat, r, lon ascending), computed from vx = 1e+30 m/s" \
    preprocess "$work/in/big.nc" -o "$work/ds" --quiet
  check "a failed fresh run leaves no output directory" test ! -e "$work/ds"
  # Finite extremes of float32 in a stored variable: the histogram bins them without overflow.
  ncdump "$fixture/spherical001.nc" |
    awk '/^ temperature =/ { after = 1; print; next } after == 1 { sub(/[-0-9.e+]+/, "3.4e38"); after = 2 }
         after == 2 && /;/ { sub(/[-0-9.e+]+ ;/, "-3.4e38 ;"); after = 3 } { print }' > "$work/extreme.cdl"
  ncgen -k nc6 -o "$work/in/extreme.nc" "$work/extreme.cdl"
  "$raypc" preprocess "$work/in/extreme.nc" -o "$work/ext" --quiet --no-pathlines >/dev/null
  check "float32 extremes preprocess" grep -q '"complete"' "$work/ext/dataset.json"
  ;;
truncated_and_fill)
  # Cuts shorter than the header (~1.4 KB) were once read as zeros with exit 0.
  size=$(stat -c %s "$fixture/spherical001.nc")
  for cut in 1 4 1000 1400; do
    head -c $((size - cut)) "$fixture/spherical001.nc" > "$work/cut$cut.nc"
    expect_error "cut$cut.nc: truncated: the file has $((size - cut)) bytes" preprocess "$work/cut$cut.nc" -o "$work/out"
  done
  check "no output after truncated inputs" test ! -e "$work/out"
  # A value never written (no _FillValue: netCDF's default fill, 9.96921e+36) is missing, not a temperature.
  ncdump "$fixture/spherical002.nc" |
    awk 'done != 1 && after { sub(/[-0-9.e+]+/, "_"); done = 1 } /^ temperature =/ { after = 1 } { print }' > "$work/unwritten.cdl"
  ncgen -k nc6 -o "$work/unwritten.nc" "$work/unwritten.cdl"
  "$raypc" preprocess "$work/unwritten.nc" -o "$work/kept" --quiet --no-pathlines >/dev/null
  check "it is kept missing: the manifest counts 1 missing point" python3 -c "
import json, sys
j = json.load(open(sys.argv[1]))
t = [v['name'] for v in j['variables']].index('temperature')
sys.exit(0 if j['steps'][0]['stats'][t].get('missing_points') == 1 else 1)" "$work/kept/dataset.json"
  "$raypc" preprocess "$work/unwritten.nc" -o "$work/filled" --fill-missing --quiet --no-pathlines >/dev/null
  check "--fill-missing fills it" python3 -c "
import json, sys
j = json.load(open(sys.argv[1]))
sys.exit(0 if all('missing_points' not in s for st in j['steps'] for s in st['stats']) else 1)" "$work/filled/dataset.json"
  ;;
huge_grid)
  # A netCDF-4 file may declare a grid larger than memory (its data never written,
  # so the file is small); the run must say so before allocating.
  make_grid() {  # make_grid NAME NLAT NR NLON
    awk -v name="$1" -v nlat="$2" -v nr="$3" -v nlon="$4" 'function axis(n, lo, hi,   i, s) {
        for (i = 0; i < n; i++) s = s (i ? ", " : "") lo + (hi - lo) * (i + 0.5) / n; return s }
      BEGIN {
        printf "netcdf %s {\ndimensions: lat = %d ; r = %d ; lon = %d ;\nvariables:\n", name, nlat, nr, nlon
        print "  double lat(lat) ; lat:units = \"degrees_north\" ; double r(r) ; r:units = \"km\" ;"
        print "  double lon(lon) ; lon:units = \"degrees_east\" ;"
        n = split("temperature vx vy vz thermal_conductivity thermal_expansivity temperature_anomaly spin_transition-induced_density_anomaly", v, " ")
        for (i = 1; i <= n; i++) { gsub(/_/, "\\ ", v[i]); printf "  float %s(lat, r, lon) ; %s:_ChunkSizes = 1, 1, %d ;\n", v[i], v[i], nlon }
        printf "data:\n  lat = %s ;\n  r = %s ;\n  lon = %s ;\n}\n", axis(nlat, -90, 90), axis(nr, 3485, 6371), axis(nlon, 0, 360)
      }' > "$work/$1.cdl"
    ncgen -k nc4 -o "$work/$1.nc" "$work/$1.cdl"
  }
  make_grid huge 1000 1000 4000
  check "the huge file is small" test "$(stat -c %s "$work/huge.nc")" -lt 10000000
  expect_error "huge.nc: grid 1000x1000x4000 (lat x r x lon) needs 192.0 GB of memory to preprocess" \
    preprocess "$work/huge.nc" -o "$work/out" --quiet
  expect_error "huge.nc: grid 1000x1000x4000 (lat x r x lon) needs 144.0 GB of memory to read" info "$work/huge.nc"
  make_grid toomany 2000 1000 4000
  expect_error "toomany.nc: grid 2000x1000x4000 (lat x r x lon) has 8000000000 points, more than the 4294967295" \
    preprocess "$work/toomany.nc" -o "$work/out" --quiet
  check "no output after grids too large" test ! -e "$work/out"
  ;;
lock)
  # Two runs into one directory. The first is stopped while it holds the lock, so
  # the second surely meets it; it must be refused, naming the holder, and leave the first intact.
  "$raypc" synth -o "$work/nc" --steps 3 --grid 48x61x96 >/dev/null 2>&1
  "$raypc" preprocess "$work/nc" -o "$work/ds" --quiet >/dev/null 2>&1 &
  pid=$!
  for _ in $(seq 1 600); do
    grep -q "pid $pid" "$work/ds/.lock" 2>/dev/null && break
    sleep 0.01
  done
  kill -STOP "$pid"
  expect_error "$work/ds: another raypc preprocess is writing this dataset (pid $pid on host $(hostname))" \
    preprocess "$work/nc" -o "$work/ds" --quiet
  kill -CONT "$pid"
  wait "$pid"; status=$?
  check "the holder finished (exit $status)" test "$status" -eq 0
  check "its dataset is complete" grep -q "steps: 3" <<<"$("$raypc" info "$work/ds")"
  out=$("$raypc" preprocess "$work/nc" -o "$work/ds" --quiet)
  check "a later run is not blocked ($out)" grep -q "0 written, 3 already done" <<<"$out"
  ;;
failed_run_leaves)
  # What a failed run may leave and what it must not (docs/format.md, "What a failed run leaves").
  mkdir -p "$work/in" "$work/empty"
  cp "$fixture"/spherical00{1,2}.nc "$work/in/"
  # Damage that only shows in the data: a variable with no value in the step (NaN everywhere).
  cp "$fixture/spherical003.nc" "$work/nan.nc"
  python3 -c "
import netCDF4, numpy, sys
with netCDF4.Dataset(sys.argv[1], 'a') as nc:
    nc.variables['temperature'][:] = numpy.nan" "$work/nan.nc"
  # A fresh run failing at its first step: nothing, in a new or an existing empty directory.
  expect_error "nan.nc: temperature: every value of the step is missing" preprocess "$work/nan.nc" -o "$work/new" --quiet
  check "no directory created" test ! -e "$work/new"
  expect_error "nan.nc: temperature: every value of the step is missing" preprocess "$work/nan.nc" -o "$work/empty" --quiet
  check "the empty directory stays empty" test -z "$(ls -A "$work/empty")"
  # Failing later: the finished steps, sample_coords.f32 and an "incomplete" manifest, nothing else.
  cp "$work/nan.nc" "$work/in/spherical003.nc"
  expect_error "(2 finished steps stay in $work/ds: a rerun resumes from them)" preprocess "$work/in" -o "$work/ds" --quiet
  check "exactly the finished steps" test "$(ls -A "$work/ds/steps")" = "$(printf '0000\n0001')"
  check "no temporary files" test -z "$(find "$work/ds" -name '.*' ! -name .lock)"
  check "the manifest says incomplete" grep -q '"status": "incomplete"' "$work/ds/dataset.json"
  check "and lists no steps" test "$(grep -c '"time_myr"' "$work/ds/dataset.json")" -eq 0
  expect_error "did not finish" info "$work/ds"
  # A write that fails (here: a file size limit) removes the step it was writing.
  cp "$fixture/spherical003.nc" "$work/in/"
  "$raypc" preprocess "$work/in/spherical00"{1,2}.nc -o "$work/ext" --quiet --no-pathlines --sample-rows 1000 >/dev/null
  err=$( (trap '' XFSZ; ulimit -f 200; "$raypc" preprocess "$work/in" -o "$work/ext" --quiet --no-pathlines --sample-rows 1000 2>&1 >/dev/null) )
  check "a failed write names the file ($err)" grep -q "steps/.0002.tmp-.*write failed" <<<"$err"
  check "and leaves no temporary directory" test -z "$(find "$work/ext" -name '.*tmp*')"
  out=$("$raypc" preprocess "$work/in" -o "$work/ds" --quiet)
  check "rerun resumes ($out)" grep -q "1 written, 2 already done" <<<"$out"
  ;;
reproducible)
  # Parallel sums once made global means differ in the last digits between runs.
  "$raypc" synth -o "$work/nc" --steps 2 --grid 48x61x96 >/dev/null 2>&1
  # Run 3 reads one step at a time (--no-read-ahead): the same bytes.
  for run in 1 2 3; do
    "$raypc" preprocess "$work/nc" -o "$work/ds$run" --quiet --pathline-steps 1 $([[ $run == 3 ]] && echo --no-read-ahead) >/dev/null
  done
  check "dataset.json of runs 1 and 2 byte-identical" cmp "$work/ds1/dataset.json" "$work/ds2/dataset.json"
  check "dataset.json of runs 1 and 3 byte-identical" cmp "$work/ds1/dataset.json" "$work/ds3/dataset.json"
  check "every file of runs 1 and 2 byte-identical" diff -r --exclude=.lock "$work/ds1" "$work/ds2"
  check "every file of runs 1 and 3 (--no-read-ahead) byte-identical" diff -r --exclude=.lock "$work/ds1" "$work/ds3"
  # The generator's truth: a row per step and feature, the same in every run.
  "$raypc" synth -o "$work/nc2" --steps 2 --grid 48x61x96 --truth "$work/truth1.csv" >/dev/null 2>&1
  "$raypc" synth -o "$work/nc3" --steps 2 --grid 48x61x96 --truth "$work/truth2.csv" >/dev/null 2>&1
  check "synth --truth: the same file twice" cmp "$work/truth1.csv" "$work/truth2.csv"
  check "  and the same series as without it" cmp "$work/nc/spherical002.nc" "$work/nc2/spherical002.nc"
  check "  its header" grep -q '^step,time_myr,feature,kind,front_depth_km,stall_depth_km,front_at_stall,' "$work/truth1.csv"
  features0=$(awk -F, 'NR > 1 && $1 == 0' "$work/truth1.csv" | wc -l)
  check "  as many features in both steps" test "$(awk -F, 'NR > 1 && $1 == 1' "$work/truth1.csv" | wc -l)" -eq "$features0"
  check "  plumes and slabs, some stalled at 660 km" test "$(awk -F, '$4 == "slab" && $6 == 660' "$work/truth1.csv" | wc -l)" -gt 0
  check "  step 1 at 2 Myr" test "$(awk -F, 'NR > 1 && $1 == 1 { print $2; exit }' "$work/truth1.csv")" = 2
  check "  every core has a volume" test "$(awk -F, 'NR > 1 && !($10 > 0)' "$work/truth1.csv" | wc -l)" -eq 0
  expect_error "truth" synth -o "$work/nc4" --steps 1 --grid 48x61x96 --truth "$work/missing/dir/truth.csv"
  check "  no slab breaks through without --avalanche" test "$(awk -F, 'NR > 1 && $13 != 0' "$work/truth1.csv" | wc -l)" -eq 0
  # An avalanche (docs/synthetic-data.md): at 2-4 Myr one slab stalled at 660 km breaks through it;
  # step 1 (2 Myr) is under way, step 0 and 2 are not.
  "$raypc" synth -o "$work/nc5" --steps 3 --grid 48x61x96 --avalanche 2:2 --truth "$work/truth3.csv" >/dev/null 2>&1
  check "synth --avalanche 2:2: one slab at 660 km breaks through, in step 1 only" \
    test "$(awk -F, 'NR > 1 && $13 == 1 { print $1 ":" $4 ":" $6 }' "$work/truth3.csv")" = "1:slab:660"
  check "  and step 0 is the series without it" cmp "$work/nc2/spherical001.nc" "$work/nc5/spherical001.nc"
  expect_error "--avalanche 'soon'" synth -o "$work/nc6" --steps 1 --grid 48x61x96 --avalanche soon
  expect_error "duration -1 Myr is not positive" synth -o "$work/nc6" --steps 1 --grid 48x61x96 --avalanche 3:-1
  ;;
cf_netcdf_options)
  # --radius-units says what the radius coordinate's numbers are (the files are the
  # reader's CF variants, tests/data/cf-variants, beside the contest layout).
  cf="$fixture/../cf-variants"
  expect_error "radius_m_no_units.nc: coordinate 'r' (radius) has no units" info "$cf/radius_m_no_units.nc"
  expect_error "--radius-units km|m|nondimensional" info "$cf/radius_nondimensional.nc"
  expect_error "--radius-units: feet not in" info "$cf/radius_m_no_units.nc" --radius-units feet
  # Read as metres the radii fit, and the file's own variables (temperature, vx) are read: the way
  # out the message gives works.
  info=$("$raypc" info "$cf/radius_m_no_units.nc" --radius-units m)
  check "--radius-units m: the file opens with its variables" grep -q "r 3485..6371 km" <<<"$info"
  check "  temperature and vx" test "$(grep -cE '^ +(temperature|vx) ' <<<"$info")" -eq 2
  "$raypc" info "$cf/radius_nondimensional.nc" --radius-units nondimensional >/dev/null
  check "--radius-units nondimensional: the file opens" test $? -eq 0
  # Three steps in one file are read as three (CfVariants), whatever its variables.
  "$raypc" preprocess "$cf/time_three_steps.nc" -o "$work/x" --quiet >/dev/null
  check "a file of three steps is a dataset of three" grep -q "steps: 3" <<<"$("$raypc" info "$work/x")"
  ;;
netcdf_inputs)
  # raypc render FILE.nc…: the files are preprocessed into --dataset first (a later run reuses it);
  # the picture is the one of a dataset preprocessed on its own with the same options.
  preprocess_fixture
  "$raypc" render "$work/ds" --time 2 --size 200x150 -o "$work/a.png" >/dev/null
  err=$("$raypc" render "$fixture"/spherical00{1,2,3}.nc --dataset "$work/series" --sample-rows 2000 \
        --time 2 --size 200x150 -o "$work/b.png" 2>&1 >/dev/null)
  check "render of netCDF files wrote the picture of the preprocessed dataset" cmp "$work/a.png" "$work/b.png"
  check "the dataset of the files is complete" "$raypc" info "$work/series"
  out=$("$raypc" render "$fixture"/spherical00{1,2,3}.nc --dataset "$work/series" --sample-rows 2000 \
        --time 1 -o "$work/c.png" 2>&1)
  check "a second render reuses the dataset ($out)" grep -q "3 of 3 steps already done" <<<"$out"
  expect_error "different 'sample'" render "$fixture"/spherical00{1,2,3}.nc --dataset "$work/series" --time 1 -o "$work/d.png"
  check "no picture from the refused run" test ! -e "$work/d.png"
  ;;
huge_pages)
  # core/system_memory.h: raypc runs itself again with glibc's malloc asking for transparent huge
  # pages when the kernel gives them only on request; RAYPC_HUGE_PAGES=0 and a hugetlb tunable the
  # user set themselves are left alone. glibc shortens GLIBC_TUNABLES in the process's memory to its
  # first tunable once parsed, so /proc shows that one; the huge pages themselves show in smaps.
  # The sample of 100 000 rows (5.6 MB, read as the server starts) is memory huge pages can back.
  "$raypc" preprocess "$fixture" -o "$work/ds" --quiet >/dev/null
  # server_memory [ENV...]: "GLIBC_TUNABLES (first tunable) AnonHugePages_kB" of a running server.
  server_memory() {
    # Emptied first: the background shell truncates the log only once it runs, and the wait below
    # once read the previous server's address in it and then a server not yet serving (flaky).
    : > "$work/serve.log"
    env "$@" "$raypc" serve "$work/ds" --port 0 > "$work/serve.log" 2>&1 &
    local pid=$!
    # Up to a minute: under a full ctest run on 2 cores a start once took longer than the 20 s
    # this waited before, and the case then read a server that was not serving yet ("none, 0 kB").
    for _ in $(seq 600); do grep -q "http://" "$work/serve.log" && break; sleep 0.1; done
    if ! grep -q "http://" "$work/serve.log"; then
      echo "FAIL: the server ($*) did not start within 60 s: $(tail -n 3 "$work/serve.log")" >&2
    fi
    local t h
    t=$(tr '\0' '\n' < "/proc/$pid/environ" | sed -n 's/^GLIBC_TUNABLES=//p')
    h=$(awk '/^AnonHugePages:/ {print $2}' "/proc/$pid/smaps_rollup")
    kill "$pid"; wait "$pid" 2>/dev/null
    echo "${t:-none} ${h:-?}"
  }
  if grep -q '\[madvise\]' /sys/kernel/mm/transparent_hugepage/enabled 2>/dev/null; then
    read -r t h <<<"$(server_memory)"
    check "the server asks for huge pages ($t)" test "$t" = "glibc.malloc.hugetlb=1"
    check "and has some ($h kB)" test "$h" -gt 0
    read -r t h <<<"$(server_memory GLIBC_TUNABLES=glibc.malloc.tcache_count=5)"
    check "with another tunable of the user's too ($t, $h kB)" test "$t" = "glibc.malloc.hugetlb=1" -a "$h" -gt 0
    read -r t h <<<"$(server_memory RAYPC_HUGE_PAGES=0)"
    check "RAYPC_HUGE_PAGES=0 leaves malloc alone ($t, $h kB)" test "$t" = none -a "$h" -eq 0
  else
    read -r t h <<<"$(server_memory)"
    check "no tunable where the kernel's policy is not madvise ($t)" test "$t" = none
  fi
  read -r t h <<<"$(server_memory GLIBC_TUNABLES=glibc.malloc.hugetlb=0)"
  check "the user's own hugetlb setting stands ($t)" test "$t" = "glibc.malloc.hugetlb=0"
  ;;
deep_json)
  # JSON nested 100 000 deep (200 KB) in a state file and in a dataset manifest
  # gets one short line (no crash, no 20 KB value quoted); 10 000 deep likewise.
  preprocess_fixture
  for depth in 100000 10000; do
    python3 -c "import sys; n=int(sys.argv[1]); print('{\"version\": 7, \"step\": ' + '['*n + ']'*n + '}')" $depth > "$work/deep.json"
    expect_error "nested deeper than" render "$work/ds" --time 0 -o "$work/deep.png" --state "$work/deep.json"
    err=$("$raypc" render "$work/ds" --time 0 -o "$work/deep.png" --state "$work/deep.json" 2>&1 >/dev/null)
    check "the message at depth $depth is short (${#err} characters)" test "${#err}" -lt 300
    check "no picture is written" test ! -e "$work/deep.png"
  done
  # A value of a wrong type, 10 000 deep inside an array, is quoted as an excerpt.
  python3 -c "print('{\"version\": 7, \"step\": 0, \"camera\": {\"azimuthDeg\": ' + '['*60 + ']'*60 + '}}')" > "$work/wide.json"
  err=$("$raypc" render "$work/ds" --time 0 -o "$work/deep.png" --state "$work/wide.json" 2>&1 >/dev/null)
  check "a refused value is quoted in a short excerpt (${#err} characters: $err)" test "${#err}" -lt 300
  cp -r "$work/ds" "$work/ds-deep"
  python3 -c "print('['*100000 + ']'*100000)" > "$work/ds-deep/dataset.json"
  expect_error "nested deeper than" info "$work/ds-deep"
  ;;
non_finite_options)
  # Every numeric option refuses NaN and infinities with one line (unchecked, probe --lon nan
  # answered null values with exit 0; --time infMyr rendered step 0; --range 0:inf ran).
  preprocess_fixture
  for v in nan inf -inf 1e999 NAN; do
    expect_error "--lon: $v is not a finite number" probe "$work/ds" --lat 0 --r 5000 --lon "$v"
  done
  expect_error "--lat: nan is not a finite number" probe "$work/ds" --lat nan --lon 0 --r 5000
  expect_error "--r: inf is not a finite number" probe "$work/ds" --lat 0 --lon 0 --r inf
  expect_error "MIN and MAX must be finite numbers" stats "$work/ds" --range "temperature=nan:5" -o "$work/s.csv"
  expect_error "MIN and MAX must be finite numbers" stats "$work/ds" --range "temperature=0:inf" -o "$work/s.csv"
  expect_error "'infMyr' is not a time like 24Myr" render "$work/ds" --time infMyr -o "$work/x.png"
  expect_error "'nanMyr' is not a time like 24Myr" probe "$work/ds" --time nanMyr --lat 0 --lon 0 --r 5000
  expect_error "--pathline-radius: inf is not a finite number" render "$work/ds" --pathline-radius inf -o "$work/x.png"
  expect_error "--dt-myr: nan is not a finite number" preprocess "$fixture" -o "$work/x" --dt-myr nan
  expect_error "--dt-myr: inf is not a finite number" synth -o "$work/sy" --dt-myr inf
  check "nothing was written" test ! -e "$work/x.png" -a ! -e "$work/s.csv" -a ! -e "$work/x" -a ! -e "$work/sy"
  ;;
aspect_series)
  # ASPECT's output (deal.II DataOut's files in tests/data/aspect-layout) preprocessed,
  # probed against its analytic truth, rendered; its times from the .pvd; bad series refused.
  aspect=$(cd "$(dirname "$0")/../data/aspect-layout" && pwd)
  "$raypc" preprocess "$aspect/shell-amr" -o "$work/amr" --quiet >"$work/pre.txt" 2>&1
  check "preprocess of the adaptive series: $(cat "$work/pre.txt")" grep -q "3 steps (3 written, 0 already done) of 133x34x266" "$work/pre.txt"
  "$raypc" info "$work/amr" >"$work/info.txt"
  check "times from the .pvd (years)" grep -q "steps: 3 (0 .. 4 Myr, 2 Myr apart; solution-00000.pvtu .. solution-00002.pvtu)" "$work/info.txt"
  check "temperature anomaly computed from T" grep -Eq "temperature anomaly .*\(computed from T when read\)" "$work/info.txt"
  check "info names the source and the resampling: $(grep source: "$work/info.txt")" \
    grep -Eq "source: VTK XML \(ASPECT layout\), resampled onto level 0; step 0: 53296 cells in 3 pieces, grid points inside a cell 9[0-9.]+ %, snapped to the nearest cell [0-9.]+ %, in none 0" "$work/info.txt"
  # At the centre of the blob at 60°N 20°E, 5300 km, step 0: T = 1600 + 2000 (6371 - 5300) / 2886 + 300
  # (+ 0.04 K from the other blobs) = 2642.2 K; the mesh interpolates within 26 K (docs/format.md).
  "$raypc" probe "$work/amr" --lat 60 --lon 20 --r 5300 --var T >"$work/probe.json"
  check "probe T at the blob's centre within 26 K of 2642.2 K: $(tr -d ' \n' <"$work/probe.json")" python3 - "$work/probe.json" <<'PY'
import json, sys
v = json.load(open(sys.argv[1]))["values"]["T"]["value"]
sys.exit(0 if abs(v - 2642.2) < 26 else 1)
PY
  "$raypc" probe "$work/amr" --lat 0 --lon 0 --r 5000 --var "radial velocity" >"$work/vr.json"
  check "radial velocity is u0 = 1 cm/yr: $(tr -d ' \n' <"$work/vr.json")" python3 - "$work/vr.json" <<'PY'
import json, sys
v = json.load(open(sys.argv[1]))["values"]["radial velocity"]["value"]
sys.exit(0 if abs(v - 1.0) < 0.01 else 1)
PY
  # The mass flux where the data have a density: truth.json's density is 3300 (1 - 3e-5
  # blob_sum) kg/m^3 and the flow u0 = 1 cm/yr outward, so across 1000 km the mass going up is
  # 3300e9 kg/km^3 x 4 pi r^2 x 1e-5 km/yr (the blobs change it by far less than 1 %) and none goes down.
  "$raypc" flux "$work/amr" --depth 1000 -o "$work/flux.csv" --quiet >/dev/null
  check "flux of a series with density has the mass columns" grep -q ',mass_down_kg_per_yr,mass_up_kg_per_yr,selected_mass_down_kg_per_yr,selected_mass_up_kg_per_yr$' "$work/flux.csv"
  check "the mass flux up across 1000 km is rho 4 pi r^2 u0: $(sed -n 2p "$work/flux.csv")" python3 - "$work/flux.csv" <<'PY'
import csv, math, sys
rows = list(csv.DictReader(open(sys.argv[1])))
r = 6371 - 1000
expected = 3300e9 * 4 * math.pi * r * r * 1e-5
ok = len(rows) == 3 and all(abs(float(x["mass_up_kg_per_yr"]) / expected - 1) < 0.01 and float(x["mass_down_kg_per_yr"]) == 0
                            and abs(float(x["mass_up_kg_per_yr"]) / (3300e9 * float(x["up_km3_per_yr"])) - 1) < 0.01 for x in rows)
sys.exit(0 if ok else 1)
PY
  "$raypc" render "$work/amr" -o "$work/amr.png" --size 96x96 --passes 1 >/dev/null
  check "a rendered picture" test -s "$work/amr.png"
  "$raypc" info "$aspect/shell-lagrange/solution.pvd" --time-units seconds >"$work/lag.txt"
  check "info of a .pvd names the resampling: $(sed -n 3,4p "$work/lag.txt")" grep -q "768 cells in 2 pieces, resampled onto 32 x 9 x 64" "$work/lag.txt"
  check "--time-units seconds" grep -q "steps: 2 (0 .. 6.3376[0-9]*e-08 Myr; the collection's times read as seconds, see --time-units)" "$work/lag.txt"
  printf '<VTKFile type="Collection"><Collection><DataSet timestep="0" file="gone/solution-00000.pvtu"/></Collection></VTKFile>' >"$work/bad.pvd"
  expect_error "which does not exist" preprocess "$work/bad.pvd" -o "$work/bad"
  expect_error "--time-units 'days'" preprocess "$aspect/shell-amr" -o "$work/bad" --time-units days
  expect_error "--grid '10x10'" preprocess "$aspect/shell-amr" -o "$work/bad" --grid 10x10
  check "no output of refused runs" test ! -e "$work/bad"
  ;;
render_memory)
  # A picture larger than the memory left is refused before allocating, with the
  # figures (a 16384x16384 render printed only "std::bad_alloc"); one that fits still renders.
  preprocess_fixture
  limited() { (ulimit -v 3000000 && "$raypc" "$@"); }  # 3 GB of address space
  err=$(limited render "$work/ds" --size 16384x16384 -o "$work/huge.png" 2>&1 >/dev/null); status=$?
  check "16384x16384 under 3 GB exits 1 (got $status)" test "$status" -eq 1
  check "one line naming the figures: $err" \
    grep -Eq '^raypc: error: a picture of 16384x16384 pixels needs [0-9.]+ GB of memory to render, [0-9.]+ (GB|MB) available \(ulimit -v\); choose a smaller --size$' <<<"$err"
  err=$(limited render "$work/ds" --size 8192x8192 --stereo side-by-side -o "$work/pair.png" 2>&1 >/dev/null)
  check "a side-by-side pair of 8192x8192 eyes is refused too: $err" grep -q "picture of 8192x8192 pixels (side-by-side stereo) needs" <<<"$err"
  check "nothing was written" test ! -e "$work/huge.png" -a ! -e "$work/pair.png"
  limited render "$work/ds" --size 256x128 --passes 1 -o "$work/small.png" >/dev/null
  check "a 256x128 picture under the same limit is written" test -s "$work/small.png"
  ;;
damaged_dataset)
  # A damaged manifest or array is one line naming the file and the field,
  # exit 1, never an internal check's abort (134).
  # expect_refusal "FRAGMENT" ARGS...: exit status 1 or 2 (not a signal), one line on stderr naming FRAGMENT.
  expect_refusal() {
    local fragment=$1; shift
    local err status
    err=$("$raypc" "$@" 2>&1 >/dev/null); status=$?
    check "raypc $* exits 1 or 2 (got $status)" test "$status" -ge 1 -a "$status" -le 2
    check "raypc $* prints one line" test "$(printf '%s\n' "$err" | wc -l)" -eq 1
    check "raypc $* names '$fragment' ($err)" grep -qF -- "$fragment" <<<"$err"
  }
  "$raypc" synth -o "$work/nc" --steps 2 --grid 12x9x16 >/dev/null
  "$raypc" preprocess "$work/nc" -o "$work/ds" --quiet --sample-rows 200 --no-pathlines >/dev/null
  "$raypc" preprocess "$work/nc" -o "$work/f32" --quiet --sample-rows 200 --no-pathlines --encoding float32 >/dev/null
  cp "$work/ds/dataset.json" "$work/manifest.json"
  sed -E 's/"brick_size": *8/"brick_size": 0/' "$work/manifest.json" > "$work/ds/dataset.json"
  check "the manifest now says brick_size 0" grep -qE '"brick_size": *0' "$work/ds/dataset.json"
  expect_refusal "$work/ds/dataset.json: brick_size: 0, expected an integer 1..64" info "$work/ds"
  expect_refusal "brick_size: 0" probe "$work/ds" --lat 0 --lon 0 --r 5000
  expect_refusal "brick_size: 0" render "$work/ds" -o "$work/x.png" --size 32x32
  expect_refusal "brick_size: 0" stats "$work/ds" -o "$work/s.csv" -q
  check "no picture from a damaged dataset" test ! -e "$work/x.png"
  # The first lat row at 500 degrees (the line after "lat_deg" holds lat[0]).
  awk '!done && prev ~ /"lat_deg"/ { sub(/-?[0-9.]+/, "500.0"); done = 1 } { print; prev = $0 }' \
    "$work/manifest.json" > "$work/ds/dataset.json"
  expect_refusal "dataset.json: levels[0].lat_deg[0]: 500.0, expected a value within [-90, 90] degrees" info "$work/ds"
  cp "$work/manifest.json" "$work/ds/dataset.json"
  "$raypc" info "$work/ds" >/dev/null
  check "the restored manifest opens" test $? -eq 0
  # A level array cut short: named at open.
  truncate -s 100 "$work/ds/steps/0001/L0/vx.u16"
  expect_refusal "steps/0001/L0/vx.u16: 100 bytes, expected 3456" info "$work/ds"
  # NaN in every value of a float32 array: probe and stats refuse it instead of printing null.
  for _ in $(seq 1728); do printf '\x00\x00\xc0\x7f'; done > "$work/f32/steps/0000/L0/temperature.f32"
  expect_refusal "steps/0000/L0/temperature.f32: point" probe "$work/f32" --lat 0 --lon 0 --r 5000 --var temperature
  expect_refusal "holds nan, expected a finite value" stats "$work/f32" --range temperature=1000:2000 -o "$work/s.csv" -q
  ;;
netcdf4_serve_quiet)
  # `raypc serve DIR` of netCDF-4 files preprocesses on a background thread, which
  # printed HDF5's error stacks (HDF5-DIAG) for the calls netCDF-C expects to fail.
  "$raypc" synth -o "$work/nc4" --steps 3 --grid 12x9x16 --format netcdf4 >/dev/null
  "$raypc" serve "$work/nc4" --port 0 --dataset "$work/nc4.raypc" > "$work/serve.log" 2>&1 &
  pid=$!
  for _ in $(seq 300); do grep -q "steps are ready" "$work/serve.log" && break; sleep 0.1; done
  kill "$pid"; wait "$pid" 2>/dev/null
  check "the whole series was served" grep -q "all 3 steps are ready" "$work/serve.log"
  diag=$(grep -c "HDF5-DIAG" "$work/serve.log")
  check "no HDF5-DIAG lines in the server's log ($diag)" test "$diag" -eq 0
  "$raypc" info "$work/nc4/spherical002.nc" > "$work/info.log" 2>&1
  check "nor from info of a netCDF-4 file" test "$(grep -c HDF5-DIAG "$work/info.log")" -eq 0
  ;;
outputs_and_options)
  # Outputs never replace a device or a link; options are checked as the state checks them; an
  # output named for another format is refused; the messages name the option.
  "$raypc" synth -o "$work/nc" --steps 2 --grid 24x21x48 >/dev/null
  "$raypc" preprocess "$work/nc" -o "$work/ds" --quiet --sample-rows 500 --no-pathlines >/dev/null
  if [[ -c /dev/full ]]; then
    expect_error "/dev/full: write failed" features "$work/ds" --range "temperature anomaly=-1000:-100" -o /dev/full --quiet
    check "/dev/full is still a character device" test -c /dev/full
  fi
  "$raypc" render "$work/ds" --size 64x64 --passes 1 -o /dev/null >/dev/null
  check "render -o /dev/null succeeds and /dev/null stays a device" test $? -eq 0 -a -c /dev/null
  mkdir -p "$work/real"
  ln -s real/stats.csv "$work/link.csv"
  "$raypc" stats "$work/ds" --range "depth=0:660" -o "$work/link.csv" --quiet >/dev/null
  check "an output through a symbolic link keeps the link" test -L "$work/link.csv"
  check "  and writes its target" grep -q '^step,' "$work/real/stats.csv"
  expect_error "-o $work/map.nc: the name says .nc but -o writes PNG" map "$work/ds" --depth 660 -o "$work/map.nc"
  expect_error "/dev/null: not a regular file (a device or a pipe); the --netcdf grid is written to a regular file" map "$work/ds" --depth 660 -o "$work/map.png" --netcdf /dev/null
  expect_error "--tracks $work/t.png: the name says .png but --tracks writes CSV" features "$work/ds" \
    --range "depth=0:660" -o "$work/f.csv" --tracks "$work/t.png"
  expect_error "--depth: expected" features "$work/ds" --range "depth=0:660" -o "$work/f.csv" --depth -5
  expect_error "--depth: expected" features "$work/ds" --range "depth=0:660" -o "$work/f.csv" --depth 1e30
  expect_error "--band-half-width: expected" features "$work/ds" --range "depth=0:660" -o "$work/f.csv" --band-half-width 1e30
  expect_error "--min-overlap: expected" features "$work/ds" --range "depth=0:660" -o "$work/f.csv" --min-overlap 2
  expect_error "--heat-capacity: 1e+300" flux "$work/ds" --range "depth=0:660" -o "$work/x.csv" --heat-flux --heat-capacity 1e300
  expect_error "--sample-rows: '-1'" preprocess "$work/nc" -o "$work/y" --sample-rows -1
  expect_error "--sample-rows: '1e11'" preprocess "$work/nc" -o "$work/y" --sample-rows 1e11
  expect_error "--sample-rows: '18446744073709551615'" preprocess "$work/nc" -o "$work/y" --sample-rows 18446744073709551615
  expect_error "a picture of 1x1 pixels has no room for the map" map "$work/ds" --depth 660 --size 1x1 -o "$work/tiny.png"
  # A non-finite value in a VTK array: one line naming it (`info` crashed on NaN, aborted on Inf).
  vtk="$(dirname "$fixture")/vtk-xml"
  expect_error "PointData f: nan at point 30 is not a number" info "$vtk/nan-value.vtu"
  expect_error "PointData f: 1e+39 at point 3 is beyond float32's range" info "$vtk/huge-value.vtu"
  check "nothing written by the refused commands" test ! -e "$work/map.nc" -a ! -e "$work/map.png" -a ! -e "$work/f.csv" \
    -a ! -e "$work/x.csv" -a ! -e "$work/y" -a ! -e "$work/tiny.png"
  ;;
tomography)
  # A global tomography model in the EMC layout (tests/data/emc-layout: depth down in km, latitude,
  # longitude with the seam stored twice, one variable vs in km/s): it opens with its own variable,
  # and what needs a flow says why instead of failing.
  emc="$(dirname "$fixture")/emc-layout"
  info=$("$raypc" info "$emc/global_vs.nc")
  check "info: a 37 x 15 x 72 grid (the seam once)" grep -q "grid: 37 x 15 x 72" <<<"$info"
  check "info: the variable vs in km/s, with its long_name" grep -qE '^ +vs +\[km/s .*Shear-wave velocity$' <<<"$info"
  named=$("$raypc" info "$emc/global_vs.nc" --map "shear velocity=vs")
  check "--map gives a model's variable any name" grep -qE '^ +shear velocity +\[km/s .*Shear-wave velocity$' <<<"$named"
  out=$("$raypc" preprocess "$emc/global_vs.nc" -o "$work/ds" 2>&1)
  check "preprocess says there are no pathlines without a velocity" grep -q "no velocity (vx, vy, vz): no pathlines" <<<"$out"
  check "the dataset holds vs alone, its long_name kept" grep -qE '^ +vs .*Shear-wave velocity$' <<<"$("$raypc" info "$work/ds")"
  check "  and no derived velocity" test "$("$raypc" info "$work/ds" | grep -c "radial velocity")" -eq 0
  # Probe at grid points equals the file (u16: within the quantisation error it reports).
  for point in "0 30 50" "45 -90 1050" "-85 175 2850"; do
    check_emc_vs "probe" "$work/ds" $point
  done
  "$raypc" render "$work/ds" --size 96x96 --passes 1 -o "$work/vs.png" >/dev/null
  check "the default view renders" test -s "$work/vs.png"
  "$raypc" map "$work/ds" --depth 50 --size 200x120 -o "$work/map.png" --netcdf "$work/map.nc" >/dev/null
  check "a map and its CF grid" test -s "$work/map.png" -a -s "$work/map.nc"
  "$raypc" stats "$work/ds" --range "vs=5.5:7" -o "$work/s.csv" -q >/dev/null
  check "stats of a brush on vs select the deep mantle" awk -F, 'NR == 2 { exit !($4 > 20 && $4 < 60) }' "$work/s.csv"
  "$raypc" features "$work/ds" --range "vs=4:4.45" -o "$work/f.csv" -q >/dev/null
  check "features of the slow shallow region" test "$(wc -l < "$work/f.csv")" -ge 2
  expect_error "no pathlines for step 0 (the model has no velocity (vx, vy, vz))" export "$work/ds" --what pathlines -o "$work/p.csv"
  expect_error "no velocity component 'vx'" features "$work/ds" --range "vs=4:4.45" -o "$work/f2.csv" --tracks "$work/t.csv"
  expect_error "no 'radial velocity' variable" flux "$work/ds" --range "vs=4:4.45" -o "$work/x.csv"
  # Its shell anomalies, computed when read (no arrays): vs anomaly in km/s and dlnVs in %.
  dsinfo=$("$raypc" info "$work/ds")
  check "info: vs anomaly [km/s], computed from vs" grep -qE '^ +vs anomaly +\[km/s .*computed from vs' <<<"$dsinfo"
  check "info: vs anomaly % [%], computed from vs" grep -qE '^ +vs anomaly % +\[% .*computed from vs' <<<"$dsinfo"
  check "  and no arrays of them" test -z "$(find "$work/ds" -name '*anomaly*')"
  "$raypc" preprocess "$emc/global_vs.nc" -o "$work/ds32" --encoding float32 --quiet >/dev/null
  # The definition, from the file with numpy: each depth's mean weighted by the dual cells' areas
  # (lat edges halfway between rows, the pole rows' half a spacing to the pole; the seam's repeated
  # column dropped), and the dual cells' volumes for a brush's selected volume.
  cat >"$work/truth.py" <<'PY'
import netCDF4, numpy as np
def truth(path):
    with netCDF4.Dataset(path) as nc:
        depth = np.asarray(nc["depth"][:], float)
        lat = np.asarray(nc["latitude"][:], float)
        lon = np.asarray(nc["longitude"][:], float)[:-1]
        vs = np.asarray(nc["vs"][:], float)[:, :, :-1]
    edges = np.concatenate([[lat[0] - (lat[1] - lat[0]) / 2], (lat[1:] + lat[:-1]) / 2, [lat[-1] + (lat[-1] - lat[-2]) / 2]])
    edges = np.radians(np.clip(edges, -90, 90))
    area = np.diff(np.sin(edges))[None, :, None] * np.ones(vs.shape)
    mean = (vs * area).sum(axis=(1, 2)) / area.sum(axis=(1, 2))
    anomaly = vs - mean[:, None, None]
    r = 6371.0 - depth[::-1]
    redges = np.concatenate([[r[0]], (r[1:] + r[:-1]) / 2, [r[-1]]])
    shell = (np.diff(redges ** 3) / 3)[::-1]
    volume = shell[:, None, None] * area * np.radians(360.0 / len(lon))
    return depth, lat, lon, vs, mean, anomaly, 100 * anomaly / mean[:, None, None], volume
PY
  for ds in ds ds32; do
    for point in "0 30 50" "45 -90 1050" "-85 175 2850" "90 0 650"; do
      read -r lat lon depth <<<"$point"
      got=$("$raypc" probe "$work/$ds" --lat "$lat" --lon "$lon" --r "$((6371 - depth))")
      check "$ds: vs anomaly and vs anomaly % at lat $lat, lon $lon, depth $depth km are their definition" \
        python3 - "$work/truth.py" "$emc/global_vs.nc" "$got" "$lat" "$lon" "$depth" <<'PY'
import json, sys
sys.path.insert(0, sys.argv[1].rsplit("/", 1)[0]); from truth import truth
depth, lat, lon, vs, mean, anomaly, percent, volume = truth(sys.argv[2])
p = json.loads(sys.argv[3])["values"]
la, lo, d = map(float, sys.argv[4:7])
k, i, j = list(depth).index(d), list(lat).index(la), list(((lon + 360) % 360)).index(lo % 360)
a, q = p["vs anomaly"], p["vs anomaly %"]
ok = abs(a["value"] - anomaly[k, i, j]) <= a["quantisation_error_max"] + 2e-6
ok &= abs(q["value"] - percent[k, i, j]) <= q["quantisation_error_max"] + 5e-5
print(a, anomaly[k, i, j], q, percent[k, i, j])
sys.exit(0 if ok else 1)
PY
    done
  done
  # Brushing dlnVs >= 1 %: the selected volume is that of the grid points where the definition is
  # (points within 1e-4 % of the edge may go either way).
  "$raypc" stats "$work/ds32" --range "vs anomaly %=1:100" -o "$work/pct.csv" -q >/dev/null
  check "stats of a brush on vs anomaly % select the definition's volume" \
    python3 - "$work/truth.py" "$emc/global_vs.nc" "$work/pct.csv" <<'PY'
import csv, sys
sys.path.insert(0, sys.argv[1].rsplit("/", 1)[0]); from truth import truth
depth, lat, lon, vs, mean, anomaly, percent, volume = truth(sys.argv[2])
row = next(csv.DictReader(open(sys.argv[3])))
want, slack = volume[percent >= 1].sum(), volume[abs(percent - 1) < 1e-4].sum()
got = float(row["selected_volume_km3"])
print(got, want, slack)
sys.exit(0 if want > 0 and abs(got - want) <= slack + 1e-6 * want else 1)
PY
  ;;
regional)
  # A regional tomography model (tests/data/emc-layout/regional_vs.nc: lat 20..55, lon -130..-65, depth
  # 25..800 km, no data east of -100 below 400 km): padded to the globe with points of no data, its
  # missing values kept missing; maps, statistics and probe are of the region.
  emc="$(dirname "$fixture")/emc-layout"
  info=$("$raypc" info "$emc/regional_vs.nc")
  check "info: regional, data within lat 20..55, lon 230..295 east" \
    grep -q "regional: data within lat 20..55 deg, lon 230..295 deg east" <<<"$info"
  check "info: vs has missing values, their share of the region said" grep -qE '^ +vs .*missing [0-9.]+ % \(of the region\)' <<<"$info"
  "$raypc" preprocess "$emc/regional_vs.nc" -o "$work/ds" --quiet >/dev/null
  for encoding in u16 float32; do
    [[ $encoding == float32 ]] && "$raypc" preprocess "$emc/regional_vs.nc" -o "$work/ds32" --quiet --encoding float32 >/dev/null
    ds=$work/ds; [[ $encoding == float32 ]] && ds=$work/ds32
    # Probe at the data's grid points equals the file; in the hole and outside the region: no data.
    for point in "20 -130 25" "37 -110 700" "55 -65 400" "40 -80 100"; do
      check_emc_vs "$encoding: probe" "$ds" $point
    done
    for point in "40 -80 600" "30 -90 800" "0 0 300" "-60 -100 100" "40 -140 100" "70 -100 100"; do
      read -r lat lon depth <<<"$point"
      got=$("$raypc" probe "$ds" --lat "$lat" --lon "$lon" --r "$((6371 - depth))" --var vs)
      check "$encoding: no data at lat $lat, lon $lon, depth $depth km" python3 -c "
import json, sys
p = json.loads(sys.argv[1])['values']['vs']
sys.exit(0 if p['value'] is None and p['no_data'] is True else 1)" "$got"
    done
  done
  # The region's volume: the dual cells of its points (half a spacing beyond the outermost), its
  # selected share of what has data.
  "$raypc" info "$work/ds" --json > "$work/info.json"
  check "the dataset's volume is the region's" python3 -c "
import json, math, sys
g = json.load(open(sys.argv[1]))['levels'][0]['grid']
rad = math.radians
lat = math.sin(rad(55.5)) - math.sin(rad(19.5))
lon = rad(66)
r0, r1 = 6371 - 800, 6371 - 25  # the outermost radii's dual cells end at the radii themselves
v = lat * lon * (r1 ** 3 - r0 ** 3) / 3
sys.exit(0 if abs(g['volume_km3'] - v) < 1e-6 * v else 1)" "$work/info.json"
  note=$("$raypc" stats "$work/ds" --range "vs=0:10" -o "$work/s.csv" 2>&1)
  check "stats say they are of the region" grep -q "a regional model: volumes and percentages are of its region (20 to 55 deg north, 230 to 295 deg east)" <<<"$note"
  check "stats: every value there is selected by vs 0..10: the region less its hole" python3 -c "
import csv, math, sys
row = next(csv.DictReader(open(sys.argv[1])))
rad = math.radians
# The hole: depth 400 < d <= 800 (points 425..800; the dual cells from 412.5 down to 800) east of -100
# (points -99..-65; the dual cells from -99.5 to -64.5), over all the region's latitudes.
shell = lambda a, b: ((6371 - a) ** 3 - (6371 - b) ** 3) / 3
lat = math.sin(rad(55.5)) - math.sin(rad(19.5))
total = lat * rad(66) * shell(25, 800)
hole = lat * rad(35) * shell(412.5, 800)
share = 100 * (total - hole) / total
sys.exit(0 if abs(float(row['selected_percent_of_mantle']) - share) < 0.01 else 1)" "$work/s.csv"
  "$raypc" map "$work/ds" --depth 100 --size 200x120 --projection orthographic --central-latitude 40 --central-meridian -100 \
    -o "$work/map.png" --netcdf "$work/map.nc" >/dev/null
  check "a map of the region and its CF grid, no data outside as _FillValue" python3 -c "
import netCDF4, numpy, sys
with netCDF4.Dataset(sys.argv[1]) as nc:
    v = [nc.variables[n] for n in nc.variables if nc.variables[n].ndim == 2][0][:]
    sys.exit(0 if numpy.ma.count_masked(v) > 0 and v.count() > 0 else 1)" "$work/map.nc"
  "$raypc" render "$work/ds" --size 96x96 --passes 1 -o "$work/vs.png" >/dev/null
  check "the default view renders" test -s "$work/vs.png"
  # A global model with a hole, filled on request: the hole takes its shell's mean, the padding none.
  "$raypc" preprocess "$emc/regional_vs.nc" -o "$work/filled" --quiet --fill-missing >/dev/null
  got=$("$raypc" probe "$work/filled" --lat 40 --lon -80 --r "$((6371 - 600))" --var vs)
  check "--fill-missing fills the hole" python3 -c "
import json, sys
sys.exit(0 if json.loads(sys.argv[1])['values']['vs']['value'] is not None else 1)" "$got"
  got=$("$raypc" probe "$work/filled" --lat 0 --lon 0 --r 6000 --var vs)
  check "  and not the padding" python3 -c "
import json, sys
sys.exit(0 if json.loads(sys.argv[1])['values']['vs']['value'] is None else 1)" "$got"
  ;;
citcoms)
  # CitcomS output (tests/data/citcoms-layout, written by h5py from CitcomS' own description): 12
  # caps of 9 x 9 x 7 nodes, two steps, as HDF5 output and as combined ASCII cap files.
  cit="$(dirname "$fixture")/citcoms-layout"
  for form in "$cit/run.0.h5" "$cit/ascii/run.cap05.0" "$cit/ascii/run.cap00.0.general"; do
    info=$("$raypc" info "$form")
    check "info $(basename "$form"): 12 caps of hexahedra, resampled" grep -q "4608 cells in 12 pieces" <<<"$info"
    check "  temperature, the velocity's components, viscosity" \
      test "$(grep -cE '^ +(temperature|vx|vy|vz|viscosity) ' <<<"$info")" -eq 5
  done
  "$raypc" preprocess "$cit" -o "$work/h5" --quiet >/dev/null
  check "the HDF5 run: 2 steps, 128.6 Myr apart (1e-4 R^2/kappa)" grep -q "steps: 2 (0 .. 128.62" <<<"$("$raypc" info "$work/h5")"
  "$raypc" preprocess "$cit/ascii" -o "$work/ascii" --quiet --temperature-scale 3000 >/dev/null
  check "the ASCII caps: 2 steps, with a temperature in K" grep -qE '^ +temperature +\[K ' <<<"$("$raypc" info "$work/ascii")"
  # The resampled temperature against its formula (nondimensional; with --temperature-scale 3000 K),
  # within the error of the caps' flat-faced hexahedra on the curved shell.
  for point in "30 60 5000" "-70 200 4000" "85 300 6000" "-10 359 3600"; do
    read -r lat lon r <<<"$point"
    for ds in h5 ascii; do
      got=$("$raypc" probe "$work/$ds" --time 1 --lat "$lat" --lon "$lon" --r "$r" --var temperature)
      check "$ds: temperature at lat $lat, lon $lon, r $r km is the formula's" python3 -c "
import json, math, sys
v = json.loads(sys.argv[1])['values']['temperature']['value']
lat, lon, r, scale = float(sys.argv[2]), float(sys.argv[3]), float(sys.argv[4]) / 6371, float(sys.argv[5])
c = math.radians(90 - lat)
t = 0.5 + 0.2 * math.cos(c) + 0.1 * math.sin(c) * math.cos(math.radians(lon)) + 0.3 * (1 - r) / 0.45 + 0.01
sys.exit(0 if abs(v / scale - t) < 0.01 else 1)" "$got" "$lat" "$lon" "$r" "$([[ $ds == ascii ]] && echo 3000 || echo 1)"
    done
  done
  # The velocity: a solid-body rotation, 100 kappa/R r sin(colat) eastward: no radial part.
  got=$("$raypc" probe "$work/h5" --lat 0 --lon 90 --r 6000)
  check "velocity: eastward 100 kappa/R r, no radial velocity" python3 -c "
import json, sys
v = json.loads(sys.argv[1])['values']
expect = 100 * 1e-6 / 6.371e6 * 6000 / 6371
sys.exit(0 if abs(v['vx']['value'] + expect) < 0.03 * expect and abs(v['radial velocity']['value']) < 0.005 else 1)" "$got"
  # A regional run (one cap over lat 10..50, lon 200..260): resampled over its extent, padded to the
  # globe with points of no data; no pathlines (the flow has gaps), probe says where there is none.
  info=$("$raypc" info "$cit/regional/run.0.h5")
  check "the regional run: data within lat 10..50, lon 200..260" \
    grep -q "regional: data within lat 10..50 deg, lon 200..260 deg east" <<<"$info"
  out=$("$raypc" preprocess "$cit/regional" -o "$work/regional" 2>&1)
  check "  no pathlines: the flow has missing values" grep -q "missing values: no pathlines" <<<"$out"
  for point in "30 230 5000" "12 201 6300" "48 258 3600"; do
    read -r lat lon r <<<"$point"
    got=$("$raypc" probe "$work/regional" --lat "$lat" --lon "$lon" --r "$r" --var temperature)
    check "  temperature at lat $lat, lon $lon, r $r km is the formula's" python3 -c "
import json, math, sys
v = json.loads(sys.argv[1])['values']['temperature']['value']
lat, lon, r = float(sys.argv[2]), float(sys.argv[3]), float(sys.argv[4]) / 6371
c = math.radians(90 - lat)
t = 0.5 + 0.2 * math.cos(c) + 0.1 * math.sin(c) * math.cos(math.radians(lon)) + 0.3 * (1 - r) / 0.45
sys.exit(0 if abs(v - t) < 0.01 else 1)" "$got" "$lat" "$lon" "$r"
  done
  got=$("$raypc" probe "$work/regional" --lat -30 --lon 100 --r 5000 --var temperature)
  check "  no data outside the region" python3 -c "
import json, sys
sys.exit(0 if json.loads(sys.argv[1])['values']['temperature']['no_data'] is True else 1)" "$got"
  expect_error "run.cap03.0: 4528 values (566 rows of 8), its header \"9 x 9 x 7\" announces 567 nodes" \
    preprocess "$cit/bad/rows/run.cap00.0" -o "$work/x"
  expect_error "11 caps of step 0 found; a full sphere has 12 (missing: 7)" info "$cit/bad/missing"
  expect_error "run.h5: no dataset 'coord'" preprocess "$cit/bad/nocoord/run.0.h5" -o "$work/x"
  expect_error "grid points lie in no cell of the mesh" info "$cit/bad/hole"
  expect_error "--temperature-scale: -5 is negative" info "$cit/run.0.h5" --temperature-scale -5
  check "no dataset from the refused runs" test ! -e "$work/x"
  ;;
resume_changed_input)
  # A resumed preprocess redoes a finished step whose input changed since (size or modification time).
  "$raypc" synth -o "$work/nc" --steps 8 --grid 48x61x96 >/dev/null 2>&1
  "$raypc" synth -o "$work/other" --steps 1 --grid 48x61x96 --seed 7 >/dev/null 2>&1
  "$raypc" preprocess "$work/nc" -o "$work/ds" --quiet --no-pathlines >/dev/null 2>&1 &
  pid=$!
  for _ in $(seq 1 600); do
    [[ -f $work/ds/steps/0000/step.json ]] && break
    sleep 0.05
  done
  kill -9 "$pid" 2>/dev/null; wait "$pid" 2>/dev/null
  check "step 0 was finished before the kill" test -f "$work/ds/steps/0000/step.json"
  cp "$work/other/spherical001.nc" "$work/nc/spherical001.nc"
  touch -d '2000-01-01' "$work/nc/spherical001.nc"
  "$raypc" preprocess "$work/nc" -o "$work/ds" --no-pathlines > "$work/resume.log" 2>&1
  check "the resumed run names the changed input" grep -q "spherical001.nc: changed since an earlier run made step 0" "$work/resume.log"
  "$raypc" preprocess "$work/nc" -o "$work/fresh" --quiet --no-pathlines >/dev/null
  for point in "--lat 10 --lon 20 --r 5000" "--lat -60 --lon 300 --r 4000"; do
    # shellcheck disable=SC2086
    check "step 0 at ($point) equals a fresh run's" test "$("$raypc" probe "$work/ds" --time 0 $point | sed 1d)" = \
      "$("$raypc" probe "$work/fresh" --time 0 $point | sed 1d)"
  done
  ;;
pair_render)
  # Two datasets side by side (docs/compare.md, "Side by side"): a state with `pair` draws the first
  # at the left half and the second at the right, each as a render of its own at half the width
  # (the second's step matched by time: its times are 3 Myr apart, the first's 2).
  "$raypc" synth -o "$work/s1" --seed 1 --steps 3 --grid 32x41x64 >/dev/null
  "$raypc" synth -o "$work/s2" --seed 2 --steps 3 --grid 32x41x64 >/dev/null
  "$raypc" preprocess "$work/s1" -o "$work/a" --quiet --no-pathlines --sample-rows 500 >/dev/null
  "$raypc" preprocess "$work/s2" -o "$work/b" --quiet --no-pathlines --sample-rows 500 --dt-myr 3 >/dev/null
  cat > "$work/half.json" <<'JSON'
{"version": 13, "step": 2, "image": {"width": 80, "height": 96}, "passes": 2,
 "color": {"variable": "temperature anomaly", "range": [-300, 300]},
 "brushes": [{"name": "temperature anomaly", "min": 50, "max": 1000}]}
JSON
  python3 -c "
import json, sys
s = json.load(open(sys.argv[1]))
s['image']['width'] = 160
s['pair'] = {'dataset': sys.argv[2], 'steps': 'time'}
json.dump(s, open(sys.argv[3], 'w'))
s['step'] = 1
del s['pair']
s['image']['width'] = 80
json.dump(s, open(sys.argv[4], 'w'))" "$work/half.json" "$work/b" "$work/pair.json" "$work/half-b.json"
  "$raypc" render "$work/a" --state "$work/pair.json" -o "$work/pair.png" --stats > "$work/pair-stats.json"
  "$raypc" render "$work/a" --state "$work/half.json" -o "$work/left.png" >/dev/null
  "$raypc" render "$work/b" --state "$work/half-b.json" -o "$work/right.png" >/dev/null
  check "the pair's picture: its left half is the first's render at half width, its right half the second's" python3 - "$work" <<'PY'
import sys
from PIL import Image, ImageChops
w = sys.argv[1]
pair, left, right = (Image.open(f"{w}/{n}.png").convert("RGB") for n in ("pair", "left", "right"))
assert pair.size == (160, 96), pair.size
assert ImageChops.difference(pair.crop((0, 0, 80, 96)), left).getbbox() is None, "left half differs"
assert ImageChops.difference(pair.crop((80, 0, 160, 96)), right).getbbox() is None, "right half differs"
assert ImageChops.difference(left, right).getbbox() is not None, "the two seeds drew the same picture"
PY
  check "the stats name the second's step matched by time (4 Myr: its step 1 at 3 Myr)" python3 -c "
import json, sys
s = json.load(open(sys.argv[1]))
sys.exit(0 if s['step'] == 2 and s['pair']['step'] == 1 and s['pair']['timeMyr'] == 3.0 else 1)" "$work/pair-stats.json"
  python3 -c "
import json, sys
s = json.load(open(sys.argv[1]))
s['pair']['dataset'] = sys.argv[2]
json.dump(s, open(sys.argv[3], 'w'))
s['pair']['dataset'] = sys.argv[4]
s['image']['width'] = 1
json.dump(s, open(sys.argv[5], 'w'))" "$work/pair.json" "$work/nowhere" "$work/missing.json" "$work/b" "$work/narrow.json"
  expect_error "pair.dataset" render "$work/a" --state "$work/missing.json" -o "$work/x.png"
  expect_error "cannot be split between a pair's two datasets" render "$work/a" --state "$work/narrow.json" -o "$work/x.png"
  expect_error "not with --view map|section" render "$work/a" --state "$work/pair.json" --view map -o "$work/x.png"
  expect_error "--dataset: only for netCDF inputs" serve "$work/a" "$work/b" --dataset "$work/c" --port 0
  check "no picture after errors" test ! -e "$work/x.png"
  ;;
compare_sphere)
  # raypc correlate and raypc spectrum on fields of known spherical harmonics written by Python's
  # netCDF4 (tests/data/harmonics, its own Legendre recurrence): amplitude A(r) = r / 1000 km of the
  # 4pi-normalised harmonics, so the power at degree l is A(r)^2 and the RMS is A(r).
  h="$(dirname "$fixture")/harmonics"
  for f in global poles regional; do
    "$raypc" preprocess "$h/$f.nc" -o "$work/$f" --encoding float32 --quiet >/dev/null
  done
  g=$work/global
  # column COLUMN FILE: the values of a CSV column (comment lines skipped), one a line.
  column() { python3 -c "
import csv, sys
rows = list(csv.DictReader(l for l in open(sys.argv[2]) if not l.startswith('#')))
print('\n'.join(r[sys.argv[1]] for r in rows))" "$1" "$2"; }
  # all_near COLUMN FILE VALUE TOL: every value of the column within TOL of VALUE.
  all_near() { column "$1" "$2" | python3 -c "
import sys
v = [float(x) for x in sys.stdin.read().split()]
sys.exit(0 if len(v) == 5 and all(abs(x - float(sys.argv[1])) <= float(sys.argv[2]) for x in v) else 1)" "$3" "$4"; }
  "$raypc" correlate "$g:y20" "$g:y20" -o "$work/self.csv" --png "$work/self.png" >/dev/null
  check "a field against itself: 1 at every depth" all_near correlation "$work/self.csv" 1 1e-9
  check "  the correlation-versus-depth picture" test -s "$work/self.png"
  "$raypc" correlate "$g:y20" "$g:y20_negative" -o "$work/neg.csv" >/dev/null
  check "against its negative: -1" all_near correlation "$work/neg.csv" -1 1e-9
  check "  RMS ratio 1" all_near rms_ratio "$work/neg.csv" 1 1e-9
  "$raypc" correlate "$g:y20" "$g:y31" -o "$work/orth.csv" >/dev/null
  check "Y(2,0) against Y(3,1): 0" all_near correlation "$work/orth.csv" 0 1e-6
  check "  the whole sphere covered" all_near area_covered_percent "$work/orth.csv" 100 1e-6
  check "the RMS of A Y(3,1) is A(r) = r / 1000 km" python3 -c "
import csv, sys
rows = [r for r in csv.DictReader(l for l in open(sys.argv[1]) if not l.startswith('#'))]
sys.exit(0 if all(abs(float(r['rms_b']) - float(r['radius_km']) / 1000) < 0.003 * float(r['radius_km']) / 1000 for r in rows) else 1)" "$work/orth.csv"
  check "the CSV's header names the columns and their units" grep -q "^depth_km,radius_km,correlation,rms_a,rms_b,rms_ratio,points,area_covered_percent,note$" "$work/orth.csv"
  # Power only at the harmonic's degree, A(r)^2, on both quadratures.
  for f in global poles; do
    "$raypc" spectrum "$work/$f:y31" --lmax 10 -o "$work/$f-y31.csv" >/dev/null
    check "$f: Y(3,1) has power A(r)^2 at degree 3 and none elsewhere" python3 -c "
import csv, sys
for r in csv.DictReader(l for l in open(sys.argv[1]) if not l.startswith('#')):
    a2 = (float(r['radius_km']) / 1000) ** 2
    p = float(r['power'])
    ok = abs(p - a2) < 1e-5 * a2 if r['degree'] == '3' else p < 1e-10 * a2
    if not ok: sys.exit(f'degree {r[\"degree\"]} at {r[\"depth_km\"]} km: {p}')" "$work/$f-y31.csv"
  done
  check "the cell-centred grid is Fejér's first rule" grep -q "quadrature: Fejér's first rule" "$work/global-y31.csv"
  check "the grid with pole rows Clenshaw–Curtis" grep -q "quadrature: Clenshaw–Curtis" "$work/poles-y31.csv"
  # Turned by 180 degrees in longitude: the same spectrum.
  "$raypc" spectrum "$g:mix" --lmax 12 -o "$work/mix.csv" --png "$work/mix.png" >/dev/null
  "$raypc" spectrum "$g:mix_turned" --lmax 12 -o "$work/turned.csv" >/dev/null
  check "turned by 180 degrees in longitude: the same power at every depth and degree" python3 -c "
import sys
a = [l.split(',') for l in open(sys.argv[1]) if l[0].isdigit()]
b = [l.split(',') for l in open(sys.argv[2]) if l[0].isdigit()]
sys.exit(0 if len(a) == 5 * 13 and all(x[:3] == y[:3] and abs(float(x[3]) - float(y[3])) <= 1e-6 * (1 + float(x[3])) for x, y in zip(a, b)) else 1)" "$work/mix.csv" "$work/turned.csv"
  check "mix: powers 1, 1/4 and 1/16 of A(r)^2 at degrees 2, 5 and 9" python3 -c "
import csv, sys
want = {'2': 1.0, '5': 0.25, '9': 0.0625}
for r in csv.DictReader(l for l in open(sys.argv[1]) if not l.startswith('#')):
    a2 = (float(r['radius_km']) / 1000) ** 2
    if abs(float(r['power']) - want.get(r['degree'], 0.0) * a2) > 1e-5 * a2: sys.exit(f'{r}')" "$work/mix.csv"
  check "  the degree-depth picture" test -s "$work/mix.png"
  # Filtering to L removes the degrees above L: mix filtered to 4 is Y(2,0); the Y(5,3) part that turning
  # changes is gone, so the filtered correlation of mix and mix_turned is 1 where the unfiltered is not.
  "$raypc" correlate "$g:mix" "$g:y20" --lmax 4 -o "$work/low.csv" >/dev/null
  check "mix filtered to degree 4 against Y(2,0): 1" all_near correlation "$work/low.csv" 1 1e-6
  "$raypc" correlate "$g:mix" "$g:mix_turned" -o "$work/turn-raw.csv" >/dev/null
  "$raypc" correlate "$g:mix" "$g:mix_turned" --lmax 4 -o "$work/turn-low.csv" >/dev/null
  check "mix against mix turned by 180 degrees, unfiltered: 1 - 2 (1/4) / (1 + 1/4 + 1/16)" \
    all_near correlation "$work/turn-raw.csv" "$(python3 -c 'print(1 - 0.5 / 1.3125)')" 1e-4
  check "  filtered to degree 4: 1" all_near correlation "$work/turn-low.csv" 1 1e-6
  # Per-degree correlation at a depth.
  "$raypc" spectrum "$g:mix" --with "$g:mix_turned" --depth 700 --lmax 10 -o "$work/deg.csv" >/dev/null
  check "per degree: r = 1 at degree 2 and 9, -1 at degree 5 (odd order turned), none elsewhere, at the shell nearest 700 km" python3 -c "
import csv, sys
rows = list(csv.DictReader(l for l in open(sys.argv[1]) if not l.startswith('#')))
got = {r['degree']: r['correlation'] for r in rows}
ok = len(rows) == 11 and all(r['depth_km'] == '771' for r in rows)
ok = ok and abs(float(got['2']) - 1) < 1e-9 and abs(float(got['9']) - 1) < 1e-9 and abs(float(got['5']) + 1) < 1e-9
ok = ok and all(got[l] == '' for l in ('1', '3', '4', '6', '7', '8', '10'))
sys.exit(0 if ok else 1)" "$work/deg.csv"
  # Missing values: the correlation over the covered area, the spectrum refused with the reason.
  "$raypc" correlate "$g:y20_holes" "$g:y20" -o "$work/holes.csv" >/dev/null
  check "missing values: 1 over the points both have" all_near correlation "$work/holes.csv" 1 1e-9
  check "  the deep shells cover less" test "$(column area_covered_percent "$work/holes.csv" | tail -1 | cut -c1-5)" = "93.30"
  expect_error "2700 point(s) without data (missing values) on the shell at depth 2171.0 km; a spectrum needs the whole sphere" \
    spectrum "$g:y20_holes" -o "$work/x.csv"
  "$raypc" correlate "$g:y20_holes" "$g:y20" --lmax 4 -o "$work/holes-low.csv" >/dev/null
  check "  with --lmax the shells with missing values are left empty, saying why" \
    test "$(grep -c 'not filtered: A has no data at 2700 point(s)' "$work/holes-low.csv")" -eq 2
  # A regional grid: the correlation over its region (B resampled onto it), the spectrum refused.
  "$raypc" correlate "$work/regional:y20" "$g:y20" -o "$work/reg.csv" >/dev/null
  check "regional A against global B: 1 over the region" all_near correlation "$work/reg.csv" 1 1e-4
  check "  the region's area: (sin 61 - sin 19) x 102 degrees of the sphere" all_near area_covered_percent "$work/reg.csv" \
    "$(python3 -c 'import math; print(100 * (math.sin(math.radians(61)) - math.sin(math.radians(19))) * math.radians(102) / (4 * math.pi))')" 1e-6
  expect_error "the grid is regional (data within lat 20..60°, lon 200..300° east); spherical harmonics need the whole sphere" \
    spectrum "$work/regional:y20" -o "$work/x.csv"
  expect_error "--lmax: the grid is regional" correlate "$work/regional:y20" "$g:y20" --lmax 4 -o "$work/x.csv"
  # A netCDF file as an input, preprocessed beside it (as serve does).
  cp "$h/poles.nc" "$work/copy.nc"
  "$raypc" correlate "$work/copy.nc:y31" "$g:y31" -o "$work/files.csv" -q >/dev/null
  check "a netCDF file as A, resampled B: about 1" all_near correlation "$work/files.csv" 1 1e-3
  # Bad input: one clear message each, nothing written.
  expect_error "A: no variable 'nope'" correlate "$g:nope" "$g:y20" -o "$work/bad.csv"
  expect_error "degree 50 is out of range 0..44" spectrum "$g:y20" --lmax 50 -o "$work/bad.csv"
  expect_error "--lmax: -2 is negative" correlate "$g:y20" "$g:y20" --lmax -2 -o "$work/bad.csv"
  expect_error "--with: needs --depth" spectrum "$g:y20" --with "$g:y31" -o "$work/bad.csv"
  expect_error "--depth: needs --with" spectrum "$g:y20" --depth 100 -o "$work/bad.csv"
  expect_error "--depth: 3000 km is outside the grid's radii" spectrum "$g:y20" --with "$g:y31" --depth 3000 -o "$work/bad.csv"
  expect_error "--time: 3 out of range 0..0" correlate "$g:y20" "$g:y20" --time 3 -o "$work/bad.csv"
  expect_error "writes CSV" correlate "$g:y20" "$g:y20" -o "$work/bad.png"
  check "nothing written by the refused runs" test ! -e "$work/bad.csv" -a ! -e "$work/x.csv"
  ;;
*) echo "unknown case $case_name"; exit 2 ;;
esac

echo "$case_name: $failures failure(s)"
[[ $failures -eq 0 ]]
