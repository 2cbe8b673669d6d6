#!/usr/bin/python3
"""Writes a small 12-cap CitcomS run with analytic fields in both forms CitcomS' output takes, for
the tests of the CitcomS reader (tests/cli, case `citcoms`).

    write_citcoms.py OUT_DIR [--nodes NXxNYxNZ --hdf5-only]   (the options: bench/open_models.sh)

Written with Python, NumPy and h5py (Debian's python3-h5py), independently of RayPC's own code,
from CitcomS' own description of its output (the public geodynamics/citcoms repository):

- the 12 caps of a full sphere with the corners CitcomS gives them (lib/Full_sphere_related.c,
  full_coord_of_cap: colatitudes 0, pi/4 + 9.736 deg, pi/2, 3 pi/4 - 9.736 deg, pi; longitudes in
  quarters), each a block of NX x NY x NZ nodes; the nodes of a cap lie between its corners (the
  normalised bilinear blend of the corners' unit vectors, so that neighbouring caps share their
  edges node for node) and on NZ radii from 0.55 to 1 (nondimensional, radius 1 = 6371 km);
- HDF5 output as lib/Output_h5.c writes it and visual/h5tocap.py reads it: `run.h5` with
  /coord[cap, nx, ny, nz, 3] (colatitude, longitude, radius) and the group /input with the
  attributes caps, radius_km, thermdiff, nodex, nodey, nodez; `run.STEP.h5` with
  /temperature[cap, nx, ny, nz], /velocity[cap, nx, ny, nz, 3] (colatitude, longitude and radial
  components), /viscosity[cap, nx, ny, nz] and the root attributes time and timestep;
- the combined cap files that visual/h5tocap.py and batchcombine.py write: `ascii/run.capNN.STEP`,
  a header line "nx x ny x nz", then a row per node (y outermost, then x, z fastest) of colatitude,
  longitude, radius, the three velocity components, temperature and viscosity, and the OpenDX
  header `run.capNN.STEP.general` of visual/dxgeneral.py.

Two steps, 0 and 100, at nondimensional times 0 and 1e-4. The fields (x, y, z = r times the unit
vector; nondimensional):

    temperature = 0.5 + 0.2 z / r + 0.1 x / r + 0.3 (1 - r) / 0.45 + 0.01 step / 100
    velocity    = solid-body rotation about z: (v_colat, v_lon, v_r) = (0, 100 r sin(colat), 0)
    viscosity   = 1 + r

Also broken inputs for the error tests: a cap file with a row missing (bad/rows), a step with a cap
missing (bad/missing), an HDF5 coordinates file without /coord (bad/nocoord), twelve caps that
do not cover the sphere (bad/hole: cap 7 written where cap 6 lies). And a regional run (regional/:
one cap over latitudes 10 ... 50 degrees north, longitudes 200 ... 260 degrees east, HDF5, step 0).
truth.json names the files and gives the formulas.
"""
import json
import math
import os
import shutil
import sys

import h5py
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # tests/data
sys.dont_write_bytecode = True  # no __pycache__ in the source tree
from fixture_dir import stamp_of, write_fixture  # noqa: E402

NX = NY = 9
NZ = 7
R_INNER = 0.55
OFFSET = 9.736 / 180.0 * math.pi
STEPS = {0: 0.0, 100: 1e-4}


def cap_corners():
    """The (colatitude, longitude) of the 4 corners of each of the 12 caps, in CitcomS' order."""
    caps = []
    for i in range(1, 5):
        north = [(0.0, 0.0), (math.pi / 4 + OFFSET, (i - 1) * math.pi / 2),
                 (math.pi / 2, (i - 1) * math.pi / 2 + math.pi / 4), (math.pi / 4 + OFFSET, i * math.pi / 2)]
        middle = [(math.pi / 4 + OFFSET, i * math.pi / 2), (math.pi / 2, i * math.pi / 2 - math.pi / 4),
                  (3 * math.pi / 4 - OFFSET, i * math.pi / 2), (math.pi / 2, i * math.pi / 2 + math.pi / 4)]
        south = [(math.pi / 2, (i - 1) * math.pi / 2 + math.pi / 4), (3 * math.pi / 4 - OFFSET, (i - 1) * math.pi / 2),
                 (math.pi, 0.0), (3 * math.pi / 4 - OFFSET, i * math.pi / 2)]
        caps += [north, middle, south]
    return caps


def unit(colat, lon):
    return np.array([math.sin(colat) * math.cos(lon), math.sin(colat) * math.sin(lon), math.cos(colat)])


def cap_nodes(corners):
    """(nx, ny, nz, 3) colatitude, longitude, radius of a cap's nodes."""
    c = [unit(*p) for p in corners]
    u, v = np.meshgrid(np.linspace(0, 1, NX), np.linspace(0, 1, NY), indexing="ij")
    p = ((1 - u) * (1 - v))[..., None] * c[0] + (u * (1 - v))[..., None] * c[1] + (u * v)[..., None] * c[2] \
        + ((1 - u) * v)[..., None] * c[3]
    p /= np.linalg.norm(p, axis=-1, keepdims=True)
    colat = np.arccos(np.clip(p[..., 2], -1.0, 1.0))
    lon = np.arctan2(p[..., 1], p[..., 0]) % (2 * math.pi)
    out = np.zeros((NX, NY, NZ, 3))
    out[..., 0] = colat[..., None]
    out[..., 1] = lon[..., None]
    out[..., 2] = np.linspace(R_INNER, 1.0, NZ)[None, None, :]
    return out


def fields(nodes, step):
    colat, lon, r = nodes[..., 0], nodes[..., 1], nodes[..., 2]
    x = np.sin(colat) * np.cos(lon)
    z = np.cos(colat)
    temperature = 0.5 + 0.2 * z + 0.1 * x + 0.3 * (1 - r) / 0.45 + 0.01 * step / 100
    velocity = np.stack([np.zeros_like(r), 100 * r * np.sin(colat), np.zeros_like(r)], axis=-1)
    viscosity = 1 + r
    return temperature, velocity, viscosity


def write_cap_file(path, nodes, temperature, velocity, viscosity, drop_row=False):
    rows = []
    for j in range(NY):
        for i in range(NX):
            for k in range(NZ):
                c, v = nodes[i, j, k], velocity[i, j, k]
                rows.append("%.6e %.6e %.6e %.6e %.6e %.6e %.6e %.6e\n"
                            % (c[0], c[1], c[2], v[0], v[1], v[2], temperature[i, j, k], viscosity[i, j, k]))
    if drop_row:
        rows.pop(len(rows) // 2)
    with open(path, "w") as fh:
        fh.write("%d x %d x %d\n" % (NX, NY, NZ))
        fh.writelines(rows)
    with open(path + ".general", "w") as fh:
        fh.write("file = %s\ngrid = %d x %d x %d\nformat = ascii\ninterleaving = field\nmajority = row\n"
                 "header = lines 1\nfield = locations, velocity, temperature, viscosity\n"
                 "structure = 3-vector, 3-vector, scalar, scalar\ntype = float, float, float, float\n\nend\n"
                 % (os.path.basename(path), NY, NX, NZ))


def write(out, hdf5_only=False):
    caps = [cap_nodes(c) for c in cap_corners()]
    coord = np.stack(caps)
    with h5py.File(os.path.join(out, "run.h5"), "w") as f:
        f.create_dataset("coord", data=coord.astype(np.float32))
        g = f.create_group("input")
        for name, value in (("caps", 12), ("nodex", NX), ("nodey", NY), ("nodez", NZ)):
            g.attrs[name] = np.int32(value)
        g.attrs["radius_km"] = np.float32(6371.0)
        g.attrs["thermdiff"] = np.float32(1e-6)
    if hdf5_only:
        for step, time in STEPS.items():
            per_cap = [fields(nodes, step) for nodes in caps]
            with h5py.File(os.path.join(out, "run.%d.h5" % step), "w") as f:
                for n, name in enumerate(("temperature", "velocity", "viscosity")):
                    f.create_dataset(name, data=np.stack([x[n] for x in per_cap]).astype(np.float32))
                f.attrs["time"] = np.float32(time)
        return
    os.makedirs(os.path.join(out, "ascii"))
    os.makedirs(os.path.join(out, "bad", "rows"))
    os.makedirs(os.path.join(out, "bad", "missing"))
    os.makedirs(os.path.join(out, "bad", "nocoord"))
    os.makedirs(os.path.join(out, "bad", "hole"))
    for step, time in STEPS.items():
        per_cap = [fields(nodes, step) for nodes in caps]
        with h5py.File(os.path.join(out, "run.%d.h5" % step), "w") as f:
            f.create_dataset("temperature", data=np.stack([t for t, _, _ in per_cap]).astype(np.float32))
            f.create_dataset("velocity", data=np.stack([v for _, v, _ in per_cap]).astype(np.float32))
            f.create_dataset("viscosity", data=np.stack([h for _, _, h in per_cap]).astype(np.float32))
            f.attrs["time"] = np.float32(time)
            f.attrs["timestep"] = np.float32(step)
        for n, (nodes, (t, v, h)) in enumerate(zip(caps, per_cap)):
            write_cap_file(os.path.join(out, "ascii", "run.cap%02d.%d" % (n, step)), nodes, t, v, h)
            if step == 0:
                write_cap_file(os.path.join(out, "bad", "rows", "run.cap%02d.0" % n), nodes, t, v, h, drop_row=(n == 3))
                if n != 7:
                    write_cap_file(os.path.join(out, "bad", "missing", "run.cap%02d.0" % n), nodes, t, v, h)
                # Twelve caps that leave a hole: cap 7 lies where cap 6 does.
                write_cap_file(os.path.join(out, "bad", "hole", "run.cap%02d.0" % n), caps[6] if n == 7 else nodes, t, v, h)
    write_regional(os.path.join(out, "regional"))
    with h5py.File(os.path.join(out, "bad", "nocoord", "run.h5"), "w") as f:
        f.create_group("input").attrs["caps"] = np.int32(12)
    shutil.copyfile(os.path.join(out, "run.0.h5"), os.path.join(out, "bad", "nocoord", "run.0.h5"))


REGIONAL_COLAT = (math.radians(40.0), math.radians(80.0))  # latitudes 10 ... 50 degrees north
REGIONAL_LON = (math.radians(200.0), math.radians(260.0))


def write_regional(out):
    """A regional run as CitcomS writes one (one cap, nodes regular in colatitude, longitude and
    radius between the cap's bounds, lib/Regional_*.c): HDF5 output, one step, the same fields."""
    os.makedirs(out)
    colat = np.linspace(*REGIONAL_COLAT, NX)
    lon = np.linspace(*REGIONAL_LON, NY)
    r = np.linspace(R_INNER, 1.0, NZ)
    nodes = np.stack(np.meshgrid(colat, lon, r, indexing="ij"), axis=-1)
    with h5py.File(os.path.join(out, "run.h5"), "w") as f:
        f.create_dataset("coord", data=nodes[None].astype(np.float32))
        g = f.create_group("input")
        for name, value in (("caps", 1), ("nodex", NX), ("nodey", NY), ("nodez", NZ)):
            g.attrs[name] = np.int32(value)
        g.attrs["radius_km"] = np.float32(6371.0)
        g.attrs["thermdiff"] = np.float32(1e-6)
    t, v, h = fields(nodes, 0)
    with h5py.File(os.path.join(out, "run.0.h5"), "w") as f:
        f.create_dataset("temperature", data=t[None].astype(np.float32))
        f.create_dataset("velocity", data=v[None].astype(np.float32))
        f.create_dataset("viscosity", data=h[None].astype(np.float32))
        f.attrs["time"] = np.float32(0.0)
        f.attrs["timestep"] = np.float32(0)


def main():
    global NX, NY, NZ
    args = sys.argv[1:]
    hdf5_only = "--hdf5-only" in args
    if "--nodes" in args:
        NX, NY, NZ = (int(n) for n in args[args.index("--nodes") + 1].split("x"))
    positional = [a for i, a in enumerate(args) if not a.startswith("--") and (i == 0 or args[i - 1] != "--nodes")]
    if len(positional) != 1:
        sys.exit("usage: write_citcoms.py OUT_DIR [--nodes NXxNYxNZ --hdf5-only]")

    def write_all(tmp):
        write(tmp, hdf5_only)
        truth = {"caps": 12, "nodes": [NX, NY, NZ], "radius_inner": R_INNER, "steps": STEPS,
                 "temperature": "0.5 + 0.2 z/r + 0.1 x/r + 0.3 (1 - r) / 0.45 + 0.01 step / 100",
                 "velocity": "(v_colat, v_lon, v_r) = (0, 100 r sin(colat), 0), in kappa/R",
                 "viscosity": "1 + r"}
        with open(os.path.join(tmp, "truth.json"), "w") as fh:
            json.dump(truth, fh, indent=1)

    write_fixture(positional[0], write_all, stamp_of([os.path.abspath(__file__)], " ".join(args[1:])))


if __name__ == "__main__":
    main()
