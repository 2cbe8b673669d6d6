#!/usr/bin/env bash
# Benchmark (not a test): the time from ASPECT's output (a VTK XML series:
# .pvd -> .pvtu -> zlib-compressed .vtu pieces) to the first picture, RayPC against ParaView in
# the same run, on the same files (bench/aspect_resample/README.md):
#   RayPC:    raypc preprocess SERIES --grid GRID --no-pathlines (one step), then
#             raypc render DATASET -o first.png --size SIZExSIZE
#   ParaView: pvbatch pv_first_picture.py: PVDReader, Resample To Image N^3, Volume coloured by T,
#             one SIZExSIZE frame saved (SaveScreenshot)
# The series is written once by write_shell.py (numpy; a ~1 M-cell cubed-sphere shell with a refined
# cap, 8 pieces, 1 step by default) into $WORK and reused when present.
# Usage: bench/aspect_resample/run.sh [write_shell.py options, e.g. --cells-per-face-edge 12 --layers 4]
# Environment: RAYPC (default BUILD/raypc, BUILD default build/), WORK (/tmp/raypc-bench-aspect),
#   GRID (180x201x360), SIZE (1024), RESAMPLE_N (256), KEEP=1 keeps the RayPC dataset.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
raypc=${RAYPC:-${BUILD:-$root/build}/raypc}
work=${WORK:-/tmp/raypc-bench-aspect}
grid=${GRID:-180x201x360}
size=${SIZE:-1024}
n=${RESAMPLE_N:-256}
py=/usr/bin/python3   # Debian's, for python3-numpy
[[ -x $raypc ]] || { echo "no $raypc: build it first (scripts/build.sh) or set RAYPC" >&2; exit 1; }

# Tools: numpy for the writer, ParaView 5.11's pvbatch and an X display for it, GNU time.
missing=()
"$py" -c 'import numpy' 2>/dev/null || missing+=(python3-numpy)
command -v pvbatch >/dev/null || missing+=(paraview python3-paraview)
command -v xvfb-run >/dev/null || missing+=(xvfb xauth)
[[ -x /usr/bin/time ]] || missing+=(time)
if ((${#missing[@]})); then
  echo "installing ${missing[*]} (apt-get)" >&2
  mkdir -p "$work"
  DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends "${missing[@]}" >"$work/apt.log" 2>&1 ||
    { echo "could not install ${missing[*]} (see $work/apt.log)" >&2; exit 1; }
fi

load_before=$(cat /proc/loadavg)

# The series, written once per set of writer options.
key=$(printf '%s' "series $*" | tr -cs 'A-Za-z0-9.' '-' | sed 's/-$//')
series=$work/$key
mkdir -p "$work"
write_s=cached
if [[ ! -f $series/solution.pvd ]]; then
  echo "writing the series to $series" >&2
  t0=$(date +%s%N)
  "$py" "$here/write_shell.py" "$series" "$@" >&2
  write_s=$(( ($(date +%s%N) - t0) / 1000000 ))ms
fi
steps=$("$py" -c 'import json,sys; print(json.load(open(sys.argv[1]))["steps"])' "$series/truth.json")
# One step for both: the series' directory when it has one step (what a user types), else the
# first step's record; ParaView's reader reads the first step only as well.
if ((steps == 1)); then input=$series; else input=$series/solution/solution-00000.pvtu; fi

warm_cache() { cat "$series"/solution/*.vtu >/dev/null; }   # both start from files in the page cache
out=$work/out-$key
mkdir -p "$out"
timed() {  # timed LOG_PREFIX command...: runs it with GNU time; wall s, peak KB, user s, sys s in LOG_PREFIX.time
  local prefix=$1; shift
  /usr/bin/time -f '%e %M %U %S' -o "$prefix.time" "$@" >"$prefix.out" 2>"$prefix.err" ||
    { echo "failed: $* (see $prefix.err)" >&2; tail -5 "$prefix.err" >&2; exit 1; }
}

# RayPC: preprocess (with -v for the per-phase seconds of the step), then render.
rm -rf "$out/dataset"
warm_cache
echo "RayPC: preprocess $input" >&2
timed "$out/preprocess" "$raypc" -v preprocess "$input" -o "$out/dataset" --grid "$grid" --no-pathlines
echo "RayPC: render" >&2
timed "$out/render" "$raypc" render "$out/dataset" -o "$out/raypc_first.png" --size "${size}x${size}"

# ParaView: the same first step through pvbatch.
warm_cache
echo "ParaView: pvbatch (Resample To Image ${n}^3)" >&2
# xvfb-run -a can hand pvbatch a display that another Xvfb on the machine takes first ("bad X server
# connection"): then it is run again, at most 3 times.
for try in 1 2 3; do
  if /usr/bin/time -f '%e %M %U %S' -o "$out/pvbatch.time" xvfb-run -a pvbatch "$here/pv_first_picture.py" \
      "$series/solution.pvd" "$out/paraview_first.png" "$size" "$n" >"$out/pvbatch.out" 2>"$out/pvbatch.err"; then
    break
  fi
  if ((try == 3)) || ! grep -q 'bad X server connection' "$out/pvbatch.err"; then
    echo "failed: pvbatch (see $out/pvbatch.err)" >&2; grep -m5 -E 'ERR|Error' "$out/pvbatch.err" >&2 || true; exit 1
  fi
  echo "pvbatch found no X display (try $try), again" >&2
done

load_after=$(cat /proc/loadavg)

"$py" - "$series" "$out" "$grid" "$size" "$n" "$write_s" "$input" "$load_before" "$load_after" \
  "$("$raypc" --version 2>&1 | head -1)" "$(pvbatch --version 2>&1 | grep -m1 -i 'paraview version' || echo pvbatch)" <<'PY'
import glob, json, os, re, sys
series, out, grid, size, n, write_s, inp, load_before, load_after, raypc_version, pv_version = sys.argv[1:]
truth = json.load(open(os.path.join(series, "truth.json")))
vtu = glob.glob(os.path.join(series, "solution", "solution-00000.*.vtu"))
mb = sum(os.path.getsize(f) for f in vtu) / 1e6

def timed(name):
    wall, kb, user, system = open(os.path.join(out, name + ".time")).read().split()[-4:]
    return float(wall), f"peak {int(kb) / 1e6:5.2f} GB, cpu {float(user) + float(system):7.2f} s"

pre_s, pre_use = timed("preprocess")
ren_s, ren_use = timed("render")
pv_wall, pv_use = timed("pvbatch")
# Per-phase seconds of the step from `raypc -v preprocess` (cumulative "done at" marks).
log = open(os.path.join(out, "preprocess.out")).read() + open(os.path.join(out, "preprocess.err")).read()
def mark(pattern):
    m = re.search(pattern + r" ([0-9.]+) s", log)
    return float(m.group(1)) if m else None
read_s, derived_at, levels_at = mark(r": read in"), mark(r": derived, stats and sample done at"), mark(r": levels, bricks and files done at")
pv = None
for line in open(os.path.join(out, "pvbatch.out")):
    if line.startswith("{"):
        pv = json.loads(line)
if pv is None:
    sys.exit(f"pvbatch printed no result (see {out}/pvbatch.err)")
cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), "?")
raypc_total = pre_s + ren_s

print(f"\nmachine: {os.cpu_count()} cores, {cpu}")
print(f"load before: {load_before}")
written = "cached from an earlier run" if write_s == "cached" else f"written in {int(write_s[:-2]) / 1000:.1f} s"
print(f"input: {series}: {truth['cells']} hexahedra ({truth['refined_cells']} from refining the {truth['refine_cap_deg']:g} deg cap), "
      f"{truth['pieces']} pieces, {truth['steps']} step(s); first step {mb:.1f} MB of .vtu ({written})")
print("files in the page cache before each; every time is a process's wall time unless said\n")
print(f"RayPC ({raypc_version}): preprocess {inp} --grid {grid} --no-pathlines; render --size {size}x{size}")
phases = ""
if None not in (read_s, derived_at, levels_at):
    phases = (f"  (read+resample {read_s:.2f}, derive/stats/sample {derived_at - read_s:.2f}, "
              f"levels/bricks/files {levels_at - derived_at:.2f}, start-up and the rest {pre_s - levels_at:.2f})")
print(f"  {'preprocess':<34} {pre_s:8.2f} s   {pre_use}{phases}")
print(f"  {'render':<34} {ren_s:8.2f} s   {ren_use}")
print(f"  {'total (time to first picture)':<34} {raypc_total:8.2f} s")
print(f"\nParaView ({pv_version}): pvbatch, PVDReader, Resample To Image {n}^3, Volume coloured by T, {size}x{size} "
      f"(VTK threads: {pv['smp_backend']}, {pv['smp_threads']})")
print(f"  {'read':<34} {pv['read']:8.2f} s   ({pv['cells']} cells, {pv['points']} points, T {pv['T_range'][0]:.0f}..{pv['T_range'][1]:.0f} K)")
print(f"  {'resample':<34} {pv['resample']:8.2f} s")
print(f"  {'frame (show, render, save)':<34} {pv['frame']:8.2f} s")
print(f"  {'total (inside pvbatch)':<34} {pv['total']:8.2f} s")
print(f"  {'pvbatch process (+ start-up, Xvfb)':<34} {pv_wall:8.2f} s   {pv_use}")
print(f"\nratio pvbatch total / RayPC total: {pv['total'] / raypc_total:.2f}x   "
      f"(with pvbatch's start-up: {pv_wall / raypc_total:.2f}x)")
print(f"load after: {load_after}")
print(f"pictures: {out}/raypc_first.png, {out}/paraview_first.png\n")
cols = [("cells", truth["cells"], "d"), ("pieces", truth["pieces"], "d"), ("raypc_pre_s", pre_s, ".2f"),
        ("raypc_render_s", ren_s, ".2f"), ("raypc_total_s", raypc_total, ".2f"), ("pv_read_s", pv["read"], ".2f"),
        ("pv_resample_s", pv["resample"], ".2f"), ("pv_frame_s", pv["frame"], ".2f"), ("pv_total_s", pv["total"], ".2f"),
        ("ratio", pv["total"] / raypc_total, ".2f")]
print("  ".join(f"{c:>{max(len(c), 8)}}" for c, _, _ in cols))
print("  ".join(f"{v:>{max(len(c), 8)}{f}}" for c, v, f in cols))
PY

if [[ ${KEEP:-0} != 1 ]]; then
  rm -rf "$out/dataset"
  echo "deleted the RayPC dataset (KEEP=1 keeps it); the series stays in $series for the next run" >&2
fi
