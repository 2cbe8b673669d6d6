#!/usr/bin/env python3
"""`raypc diff` on datasets preprocessed from files written by independent writers (Python's
netCDF4 here and in tests/data): diff_cli.py RAYPC CONTEST_LAYOUT_DIR.

- A − A is 0 everywhere (every variable's range over all steps is [0, 0]).
- A − B, B the contest-layout files with c(lat, lon) = 30 cos(lat) cos(lon) K added to the temperature:
  −c at grid points, every other variable 0; its map at 660 km (CF netCDF) is −c.
- A − C, C another grid (lat every 10°, 21 shells, lon every 10°) with T = 3 lat + 0.02 r (linear in
  C's own coordinates, so the sampler's trilinear rule is exact): A's temperature − (3 lat + 0.02 r).
- Regional: the EMC fixture's regional model minus its global one (the same formula) is about 0;
  global minus regional is missing outside the region.
- --steps 1: X(t) − X(t−1) at X(t)'s time, equal to the difference of probes.
- Each refusal: one line on stderr, exit 1, naming the problem.
"""
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile

import netCDF4
import numpy as np

raypc, fixture = sys.argv[1], sys.argv[2]
emc = os.path.join(os.path.dirname(fixture), "emc-layout")
work = tempfile.mkdtemp(prefix="raypc-diff-")
failures = 0


def check(what, ok):
    global failures
    print(("ok: " if ok else "FAIL: ") + what)
    failures += 0 if ok else 1


def run(*args):
    p = subprocess.run([raypc, *args], capture_output=True, text=True)
    if p.returncode != 0:
        raise SystemExit(f"raypc {' '.join(args)} failed: {p.stderr}")
    return p.stdout


def expect_error(fragment, *args):
    p = subprocess.run([raypc, *args], capture_output=True, text=True)
    lines = p.stderr.strip().splitlines()
    check(f"raypc {' '.join(args)} -> {p.stderr.strip()!r} names {fragment!r}",
          p.returncode == 1 and len(lines) == 1 and fragment in lines[0])


def w(name):
    return os.path.join(work, name)


def preprocess(inputs, out, *extra):
    run("preprocess", *inputs, "-o", out, "-q", "--no-pathlines", "--encoding", "float32", "--sample-rows", "500",
        *extra)
    return out


def diff(*args):
    return run("diff", *args, "-q", "--encoding", "float32")


def info(ds):
    return json.loads(run("info", ds, "--json"))


def probe(ds, lat, lon, r, var, time="0"):
    p = json.loads(run("probe", ds, "--lat", str(lat), "--lon", str(lon), "--r", str(r), "--var", var, "--time", time))
    return p["values"][var]["value"]


def write_grid_file(path, lat, r, lon, name, units, values):
    """A CF netCDF file with one variable on (lat, r, lon), as a model or tool writes it."""
    with netCDF4.Dataset(path, "w", format="NETCDF3_64BIT_OFFSET") as f:
        for dim, coords, u in (("lat", lat, "degrees_north"), ("r", r, "km"), ("lon", lon, "degrees_east")):
            f.createDimension(dim, len(coords))
            v = f.createVariable(dim, "f8", (dim,))
            v.units = u
            v[:] = coords
        v = f.createVariable(name, "f4", ("lat", "r", "lon"))
        v.units = units
        v[:] = values


try:
    files = sorted(os.path.join(fixture, f) for f in os.listdir(fixture) if f.endswith(".nc"))
    a = preprocess(files, w("a.ds"))
    a1 = preprocess(files[:1], w("a1.ds"))

    # A − A: zero everywhere, every variable (stored, derived, computed when read).
    diff(a, a, "-o", w("zero.ds"))
    zero = info(w("zero.ds"))
    check("A − A has A's 3 steps", len(zero["steps"]) == 3)
    check("A − A is 0 everywhere (every variable's range over all steps is [0, 0])",
          all(v["min"] == 0 and v["max"] == 0 for v in zero["variables"]) and len(zero["variables"]) >= 10)

    # B: the contest files with c(lat, lon) added to the temperature, written with netCDF4.
    os.mkdir(w("b"))
    for f in files:
        out = os.path.join(w("b"), os.path.basename(f))
        shutil.copy(f, out)
        with netCDF4.Dataset(out, "r+") as nc:
            lat = np.radians(nc["lat"][:])[:, None, None]
            lon = np.radians(nc["lon"][:])[None, None, :]
            nc["temperature"][:] = nc["temperature"][:] + (30 * np.cos(lat) * np.cos(lon)).astype(np.float32)
    b = preprocess(sorted(os.path.join(w("b"), f) for f in os.listdir(w("b"))), w("b.ds"))
    diff(a, b, "-o", w("d.ds"))
    d = info(w("d.ds"))
    by_name = {v["name"]: v for v in d["variables"]}
    check("A − B: every variable but the temperature is 0",
          all(v["min"] == 0 and v["max"] == 0 for n, v in by_name.items() if n != "temperature"))
    check("A − B: the temperature spans about ±30 K",
          -30.01 < by_name["temperature"]["min"] < -29 and 29 < by_name["temperature"]["max"] < 30.01)
    check("A − B keeps names and units, its long_name says what it is the difference of",
          by_name["temperature"]["units"] == "K" and by_name["temperature"]["long_name"] == "temperature of a.ds − b.ds")
    check("info --json says what the difference is",
          d["difference"]["b"].endswith("b.ds") and d["difference"]["match"] == "index")
    worst = 0.0
    for lat in (-87.5, -42.5, 2.5, 57.5, 87.5):
        for lon in (0, 5, 175, 355):
            for r in (3485, 4206.5, 6371):
                got = probe(w("d.ds"), lat, lon, r, "temperature", "2")
                worst = max(worst, abs(got + 30 * math.cos(math.radians(lat)) * math.cos(math.radians(lon))))
    check(f"A − B at grid points is −30 cos(lat) cos(lon) K (worst error {worst:.2g} K)", worst < 2e-3)
    text = run("info", w("d.ds"))
    check("raypc info names the difference", "difference: " in text and "steps paired by index" in text)
    check("a difference has no pathlines, the manifest says why",
          "difference" in json.load(open(w("d.ds/dataset.json")))["no_pathlines"])
    again = diff(a, b, "-o", w("d.ds"))
    check("a rerun resumes (nothing to write)", "(0 written, 3 already done)" in again)

    # Chosen variables: a derived one named with its inputs is derived again from their differences.
    diff(a, b, "--variable", "vx", "--variable", "vy", "--variable", "vz", "--variable", "radial velocity",
         "-o", w("v.ds"))
    v = {x["name"]: x for x in info(w("v.ds"))["variables"]}
    check("--variable vx, vy, vz, radial velocity: the velocity stored, the radial velocity derived again",
          [n for n, x in v.items() if not x["derived"]] == ["vx", "vy", "vz"] and v["radial velocity"]["derived"])
    # Paired by index, times that differ: D has A's times, and raypc diff says so once.
    b3 = preprocess(sorted(os.path.join(w("b"), f) for f in os.listdir(w("b"))), w("b3.ds"), "--dt-myr", "3")
    p = subprocess.run([raypc, "diff", a, b3, "-o", w("d3.ds"), "-q"], capture_output=True, text=True)
    check("index pairing of other times warns once and keeps A's times",
          p.returncode == 0 and (p.stdout + p.stderr).count("paired by index") == 1 and
          [x["time_myr"] for x in info(w("d3.ds"))["steps"]] == [0.0, 2.0, 4.0])

    # Like any other dataset: rendered, mapped and exported as CF netCDF.
    run("render", w("d.ds"), "--var", "temperature", "--size", "64x64", "--passes", "1", "-o", w("d.png"))
    check("D renders", os.path.getsize(w("d.png")) > 0)
    run("map", w("d.ds"), "--var", "temperature", "--depth", "660", "--size", "256x160", "-o", w("map.png"),
        "--netcdf", w("map.nc"))
    with netCDF4.Dataset(w("map.nc")) as nc:
        var = next(v for v in nc.variables.values() if v.dimensions == ("lat", "lon"))
        lat = np.radians(nc["lat"][:])[:, None]
        lon = np.radians(nc["lon"][:])[None, :]
        err = float(np.nanmax(np.abs(var[:] + 30 * np.cos(lat) * np.cos(lon))))
    check(f"D's map at 660 km (CF netCDF) is −30 cos(lat) cos(lon) K (worst {err:.2g} K)", err < 0.2)

    # C on another grid, T linear in its own coordinates: the sampler's rule gives it exactly.
    c_lat = np.arange(-80, 81, 10.0)
    c_r = np.linspace(3485, 6371, 21)
    c_lon = np.arange(0, 360, 10.0)
    write_grid_file(w("c.nc"), c_lat, c_r, c_lon, "temperature", "K",
                    (3 * c_lat[:, None, None] + 0.02 * c_r[None, :, None] + 0 * c_lon[None, None, :]))
    c = preprocess([w("c.nc")], w("c.ds"))
    diff(a1, c, "-o", w("dc.ds"))
    dc = info(w("dc.ds"))
    check("A − C differences the one variable both have",
          [v["name"] for v in dc["variables"] if v["stored"]] == ["temperature"])
    worst = 0.0
    for lat in (-77.5, -2.5, 42.5, 77.5):
        for lon in (0, 5, 180, 355):
            for r in (3485, 4927.5, 6371):
                got = probe(w("dc.ds"), lat, lon, r, "temperature")
                want = probe(a1, lat, lon, r, "temperature") - (3 * lat + 0.02 * r)
                worst = max(worst, abs(got - want))
    check(f"A − C on another grid is A − (3 lat + 0.02 r) at A's grid points (worst {worst:.2g} K)", worst < 2e-3)

    # Regional: the same formula on a regional and on the global grid.
    glob = preprocess([os.path.join(emc, "global_vs.nc")], w("global.ds"))
    reg = preprocess([os.path.join(emc, "regional_vs.nc")], w("regional.ds"))
    diff(reg, glob, "-o", w("rg.ds"))
    rg = {v["name"]: v for v in info(w("rg.ds"))["variables"]}
    check(f"regional − global is about 0 (range {rg['vs']['min']:.2g} .. {rg['vs']['max']:.2g} km/s)",
          abs(rg["vs"]["min"]) < 2e-3 and abs(rg["vs"]["max"]) < 2e-3)
    diff(glob, reg, "-o", w("gr.ds"))
    gr = info(w("gr.ds"))
    check(f"global − regional is missing outside the region ({gr['variables'][0]['missing_percent']:.3g} %)",
          gr["variables"][0]["missing_percent"] > 50 and 0 < gr["difference"]["covered_fraction"] < 0.5)

    # Step differences.
    diff(a, "--steps", "1", "-o", w("s1.ds"))
    s1 = info(w("s1.ds"))
    check("--steps 1: 2 steps at A's steps 1 and 2's times",
          [s["time_myr"] for s in s1["steps"]] == [2.0, 4.0] and s1["difference"]["step_lag"] == 1)
    worst = 0.0
    for t in (0, 1):
        for lat, lon, r in ((33, 359.5, 5000), (-61, 12, 3600), (5, 181, 6300)):
            got = probe(w("s1.ds"), lat, lon, r, "temperature", str(t))
            want = probe(a, lat, lon, r, "temperature", str(t + 1)) - probe(a, lat, lon, r, "temperature", str(t))
            worst = max(worst, abs(got - want))
    check(f"--steps 1 is X(t) − X(t−1) (worst {worst:.2g} K)", worst < 1e-3)
    rv = {v["name"]: v for v in s1["variables"]}["radial velocity"]
    check("the radial velocity is derived again (the fixture's is uniform: its step difference is 0)",
          abs(rv["min"]) < 1e-6 and abs(rv["max"]) < 1e-6)

    # Refusals.
    write_grid_file(w("far.nc"), c_lat, np.linspace(1000, 2000, 5), c_lon, "temperature", "K",
                    np.zeros((len(c_lat), 5, len(c_lon))))
    far = preprocess([w("far.nc")], w("far.ds"))
    expect_error("do not overlap", "diff", a1, far, "-o", w("x.ds"))
    # The same refusal for a correlation (app/compare_fields.h), and nothing written.
    expect_error("does not overlap A's grid", "correlate", a1 + ":temperature", far + ":temperature", "-o", w("x.csv"))
    check("no CSV after the refused correlation", not os.path.exists(w("x.csv")))
    expect_error("a1.ds and global.ds have no stored variable in common", "diff", a1, glob, "-o", w("x.ds"))
    expect_error("variable 'vx': c.ds has no such variable", "diff", a1, c, "--variable", "vx", "-o", w("x.ds"))
    expect_error("variable 'pressure': a.ds has no such variable", "diff", a, b, "--variable", "pressure",
                 "-o", w("x.ds"))
    expect_error("a.ds has 3 steps and c.ds has 1", "diff", a, c, "-o", w("x.ds"))
    expect_error("c.ds has no step at a.ds's step 1 (2 Myr): its nearest is step 0 at 0 Myr", "diff", a, c,
                 "--match", "time", "-o", w("x.ds"))
    expect_error("--steps: 3 out of range 1..2 (a.ds has 3 steps)", "diff", a, "--steps", "3", "-o", w("x.ds"))
    expect_error("--steps: 0, expected a step lag k >= 1", "diff", a, "-o", w("x.ds"))
    expect_error("not both", "diff", a, b, "--steps", "1", "-o", w("x.ds"))
    expect_error("--match: 'nearest', expected 'index' or 'time'", "diff", a, b, "--match", "nearest", "-o", w("x.ds"))
    expect_error("holds a dataset made with a different 'difference'", "diff", b, a, "-o", w("d.ds"))
    expect_error("holds a dataset made with a different 'difference'", "diff", a, b, "-o", w("c.ds"))
    check("a refused run into another dataset leaves it whole", info(w("c.ds"))["variables"][0]["name"] == "temperature")
    check("a refused run writes nothing new", not os.path.exists(w("x.ds")))
finally:
    shutil.rmtree(work, ignore_errors=True)

print(f"{failures} failure(s)")
sys.exit(1 if failures else 0)
