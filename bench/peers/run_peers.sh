#!/usr/bin/env bash
# Benchmark (not a test): RayPC's spherical ray caster side by side with what a user would otherwise
# do, in the same run, on the same full-resolution (180x201x360) synthetic netCDF step, same image size
# and view (bench/peers/peers.py has the view and transfer function; render_bench.cpp uses the same):
#   ParaView 5.11 (pvbatch): NetCDF reader, spherical coordinates, dims (lat, r, lon), Resample To Image
#                            (N^3), volume representation
#   VTK vtkFixedPointVolumeRayCastMapper (from pvbatch's Python) on the same resampled image,
#                            sample distance half a voxel
#   RayPC: raypc render --stats on the preprocessed step: one interactive pass (--lod auto, 50 ms budget),
#          one full-resolution pass, and the converged full-resolution image (passes as measured by
#          bench/render_bench BM_Converged1024)
# Prints a table with ratios (peer time / RayPC time). Installs its peers (apt-get) if missing.
# Usage: bench/peers/run_peers.sh [BUILD_DIR] [SIZE=1024] [RESAMPLE_N=256] [CONVERGED_PASSES=4]
# Data lives in $WORK (default /tmp/raypc-peers) and the big files are deleted at the end
# (KEEP=1 keeps them).
set -euo pipefail
. "$(dirname "$0")/../common.sh"
build=${1:-$root/build-perf}
size=${2:-1024}
n=${3:-256}
converged=${4:-4}
work=${WORK:-/tmp/raypc-peers}
frames=${FRAMES:-5}
raypc=$build/raypc
[[ -x $raypc ]] || { echo "no raypc in $build: build it first (cmake --build $build --target raypc)" >&2; exit 1; }

# Peers: ParaView 5.11 from Debian (paraview, python3-paraview) and xvfb for an X display.
missing=()
command -v pvbatch >/dev/null || missing+=(paraview python3-paraview)
command -v xvfb-run >/dev/null || missing+=(xvfb xauth)
if ((${#missing[@]})); then
  echo "installing ${missing[*]} (apt-get; this is large)" >&2
  apt-cache policy "${missing[@]}" | grep -E '^[a-z]|Candidate' >&2 || true
  if ! DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends "${missing[@]}" >"$work.apt.log" 2>&1; then
    echo "MISSING: could not install ${missing[*]} (see $work.apt.log); peers will not be measured" >&2
  fi
fi
have_pv=0
command -v pvbatch >/dev/null && command -v xvfb-run >/dev/null && have_pv=1

mkdir -p "$work"
nc=$work/nc/spherical001.nc
if [[ ! -f $nc ]]; then
  echo "writing the full-resolution synthetic step to $work/nc" >&2
  "$raypc" synth -o "$work/nc" --grid 180x201x360 --steps 1 >/dev/null
fi
if [[ ! -d $work/dataset ]]; then
  echo "preprocessing into $work/dataset" >&2
  "$raypc" preprocess "$nc" -o "$work/dataset" --quiet >/dev/null
fi

var="temperature anomaly"
state=$work/state.json
cat >"$state" <<JSON
{"version": 1,
 "camera": {"azimuthDeg": 30, "elevationDeg": 20, "distanceKm": 19000, "fovYDeg": 42},
 "image": {"width": $size, "height": $size},
 "color": {"variable": "$var", "colorMap": "blue-white-red", "range": [-400, 400],
           "opacity": [[0, 0.6], [0.4, 0], [0.6, 0], [1, 0.6]], "opacityUnitKm": 100},
 "timeBudgetMs": 50}
JSON

echo "machine: $(machine); load: $(cut -d' ' -f1-3 /proc/loadavg)"
echo "data: $(du -h "$nc" | cut -f1) $nc (180x201x360), image ${size}x${size}, variable '$var'"

# RayPC: seconds of the render passes (from --stats), best of 3 runs.
raypc_seconds() {  # args: lod passes -> seconds (sum over passes) and level
  local best="" level=""
  for _ in 1 2 3; do
    local json
    json=$("$raypc" render "$work/dataset" --state "$state" --lod "$1" --passes "$2" -o "$work/raypc_$1_$2.png" --stats)
    local s
    s=$(python3 -c 'import json,sys; d=json.load(sys.stdin); print(d["seconds"], d["level"])' <<<"$json")
    if [[ -z $best ]] || python3 -c "import sys; sys.exit(0 if ${s% *} < $best else 1)"; then best=${s% *}; level=${s#* }; fi
  done
  echo "$best $level"
}
read -r rp_auto rp_auto_level < <(raypc_seconds auto 1)
read -r rp_one _ < <(raypc_seconds 0 1)
read -r rp_conv _ < <(raypc_seconds 0 "$converged")

pv_frame="" vtk_frame="" pv_first="" vtk_first="" resample=""
if ((have_pv)); then
  out=$(cd "$work" && timeout 3600 xvfb-run -a pvbatch "$root/bench/peers/peers.py" both "$nc" "$size" "$frames" "$n" "$var" 2>&1 | tee "$work/peers.log" | grep -E '^(RESULT|vtk:)' || true)
  echo "$out" | grep '^vtk:' || true
  get() { echo "$out" | awk -v p="$1" -v w="$2" '$1=="RESULT" && $2==p && $3==w {print $4}'; }
  pv_frame=$(get paraview frame); pv_first=$(get paraview first_frame)
  vtk_frame=$(get vtk frame); vtk_first=$(get vtk first_frame)
  resample=$(echo "$out" | awk '$1=="RESULT" && $3 ~ /^resample/ {print $4}')
  read_s=$(echo "$out" | awk '$1=="RESULT" && $3=="read" {print $4}')
  echo "peers: read ${read_s:-?} s, Resample To Image ${n}^3 ${resample:-?} s (once, not in the frame times)"
fi

python3 - "$rp_auto" "$rp_auto_level" "$rp_one" "$rp_conv" "$converged" "${pv_frame:-}" "${pv_first:-}" "${vtk_frame:-}" "${vtk_first:-}" "$size" <<'PY'
import sys
a = sys.argv[1:]
auto, level, one, conv, passes = float(a[0]), a[1], float(a[2]), float(a[3]), a[4]
pv, pvfirst, vtk, vtkfirst, size = a[5], a[6], a[7], a[8], a[9]
def f(x): return float(x) if x else None
pv, pvfirst, vtk, vtkfirst = f(pv), f(pvfirst), f(vtk), f(vtkfirst)
rows = [(f"RayPC interactive pass (--lod auto -> level {level})", auto),
        ("RayPC one full-resolution pass", one),
        (f"RayPC converged full resolution ({passes} passes)", conv)]
print(f"\n{'renderer, ' + size + 'x' + size:<58} {'seconds':>9}")
for name, s in rows:
    print(f"{name:<58} {s:9.3f}")
for name, s in [("ParaView 5.11 volume representation, per frame", pv), ("ParaView first frame", pvfirst),
                ("VTK vtkFixedPointVolumeRayCastMapper, per frame", vtk), ("VTK first frame", vtkfirst)]:
    print(f"{name:<58} {s:9.3f}" if s is not None else f"{name:<58} {'MISSING':>9}")
print("\nratios (peer frame time / RayPC time; goals: >= 20x ParaView, >= 2x VTK)")
for peer, s in [("ParaView", pv), ("VTK fixed-point", vtk)]:
    if s is None:
        print(f"  {peer}: not measured (peer missing)")
        continue
    print(f"  {peer:<16} vs interactive pass {s / auto:7.1f}x   vs full-res pass {s / one:7.1f}x   vs converged {s / conv:7.1f}x")
PY

if [[ ${KEEP:-0} != 1 ]]; then
  rm -rf "$work/nc" "$work/dataset"
  echo "deleted the netCDF file and the dataset in $work (KEEP=1 keeps them)"
fi
