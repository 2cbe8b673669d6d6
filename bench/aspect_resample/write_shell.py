#!/usr/bin/python3
"""Writes a spherical-shell time series in the layout of ASPECT's visualization output, for
bench/aspect_resample/run.sh: a writer independent of RayPC's reader (Python 3 + numpy, zlib, base64).

    write_shell.py OUTDIR [--cells-per-face-edge N] [--layers L] [--refine-cap-deg D]
                          [--pieces P] [--steps S] [--header-type UInt32|UInt64] [--zlib-level Z]

Mesh, as deal.II's GridGenerator::hyper_shell refined and written by DataOut (what ASPECT uses):
a cubed sphere between 3485 km and 6371 km (points in metres), 6 cube faces of N x N columns
(equiangular: the cube coordinate is tan(pi/4 s), s uniform in [-1, 1]) and L layers uniform in
radius. Every hexahedron's 8 vertices lie on the inner and outer spheres of its layer, in VTK's
order (0-3 on the inner sphere counter-clockwise seen from outside, 4-7 above them), so each cell's
trilinear map has a positive Jacobian (checked before writing). The columns whose centre is within
D degrees of the north pole (+z) are refined 2x2x2 with their new vertices on the spheres, so
that hanging nodes lie on the rim of that cap, as in ASPECT's adaptive meshes. Every cell writes its
own 8 points (points repeated per cell), as DataOut does.

Files: OUTDIR/solution.pvd (times 0, 2e6, ... years) -> OUTDIR/solution/solution-NNNNN.pvtu ->
solution-NNNNN.PPPP.vtu: UnstructuredGrid, VTK_HEXAHEDRON (12), inline binary DataArrays compressed
with vtkZLibDataCompressor (32768-byte blocks; the header [nblocks, blocksize, lastblocksize,
compressed sizes...] base64-encoded apart from the concatenated compressed blocks), connectivity
and offsets Int32 (Int64 with --header-type UInt64), FieldData TIME (Float32, years), point data
Float32. OUTDIR/truth.json gives the counts, formulas and constants.

Fields (the formulas of tests/data/aspect-layout/shell-amr/truth.json, t in years):
    velocity = omega (-y, x, 0) + u0 p/|p|                        m/year
    T        = 1600 + 2000 (6371e3 - |p|) / 2886e3 + blob_sum      K
    p        = 3300 * 9.81 * (6371e3 - |p|)                        Pa
    density  = 3300 (1 - 3e-5 blob_sum)                            kg/m^3
    blob_sum = sum amp exp(-d_km^2 / (2 sigma^2)), d_km the distance to the blob's centre at
               (lat, lon + degrees(omega t), r_km + u0 t / 1000); at t = 0 the centres are as listed.
"""
import argparse
import base64
import json
import math
import os
import shutil
import sys
import tempfile
import time
import zlib

import numpy as np

R_INNER_M = 3485e3
R_OUTER_M = 6371e3
OMEGA_RAD_PER_YEAR = 1.5707963267948965e-08
U0_M_PER_YEAR = 0.01
DT_YEARS = 2e6
# (lat deg, lon deg, r km, amplitude K, sigma km)
BLOBS = [(-30, 100, 4600, 400, 600), (35, 210, 5500, -350, 550), (10, 320, 4100, -300, 650), (60, 20, 5300, 300, 500)]
VTK_HEXAHEDRON = 12
BLOCK_BYTES = 32768  # vtkZLibDataCompressor's block size as VTK writes it

# Cube faces as (outward normal n, u, v) with u x v = n, so that (u, v, radial) is right-handed and
# VTK's vertex order gives positive volumes.
FACES = [
    ((1, 0, 0), (0, 1, 0), (0, 0, 1)),
    ((-1, 0, 0), (0, 0, 1), (0, 1, 0)),
    ((0, 1, 0), (0, 0, 1), (1, 0, 0)),
    ((0, -1, 0), (1, 0, 0), (0, 0, 1)),
    ((0, 0, 1), (1, 0, 0), (0, 1, 0)),
    ((0, 0, -1), (0, 1, 0), (1, 0, 0)),
]
# VTK hexahedron corners in (u, v, radial) steps.
HEX_CORNERS = np.array([(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)])


def cells(n, layers, cap_deg):
    """Every cell as (face, i, j, k, h) on the lattice of twice the resolution (2N x 2N x 2L per face):
    the corner of smallest index and the edge length h in lattice steps (2 coarse, 1 refined),
    ordered by face, column and layer, the children of a refined cell in its place."""
    lattice = np.arange(n) * 2 + 1  # column centres on the fine lattice
    ci, cj = np.meshgrid(lattice, lattice, indexing="ij")
    out = []
    for face, (nrm, u, v) in enumerate(FACES):
        a, b = np.tan(np.pi / 4 * (ci / n - 1)), np.tan(np.pi / 4 * (cj / n - 1))
        centre = np.array(nrm)[:, None, None] + a * np.array(u)[:, None, None] + b * np.array(v)[:, None, None]
        polar_deg = np.degrees(np.arccos(centre[2] / np.linalg.norm(centre, axis=0)))
        refined = polar_deg < cap_deg
        for is_refined in (False, True):
            cols = np.argwhere(refined == is_refined)  # (i, j) coarse indices
            if not len(cols):
                continue
            k = np.arange(layers)
            if not is_refined:
                c = np.stack(np.broadcast_arrays(cols[:, None, 0], cols[:, None, 1], k[None, :]), -1).reshape(-1, 3) * 2
                h = 2
            else:
                child = np.array([(di, dj, dk) for dk in (0, 1) for dj in (0, 1) for di in (0, 1)])
                c = (np.stack(np.broadcast_arrays(cols[:, None, None, 0], cols[:, None, None, 1], k[None, :, None]), -1) * 2
                     + child[None, None, :, :]).reshape(-1, 3)
                h = 1
            out.append(np.column_stack([np.full(len(c), face), c, np.full(len(c), h)]))
    allc = np.concatenate(out)
    # order by face, column (j, i), then the coarse layer, so that a piece is a contiguous region
    order = np.lexsort((allc[:, 3], allc[:, 3] // 2, allc[:, 1] // 2, allc[:, 2] // 2, allc[:, 0]))
    return allc[order]


def points(cell_rows, n, layers):
    """The 8 vertices of each cell in VTK's order, in metres: (ncells * 8, 3) float64."""
    face, base, h = cell_rows[:, 0], cell_rows[:, 1:4], cell_rows[:, 4]
    idx = base[:, None, :] + HEX_CORNERS[None, :, :] * h[:, None, None]  # (ncells, 8, 3) lattice indices
    a = np.tan(np.pi / 4 * (idx[..., 0] / n - 1))
    b = np.tan(np.pi / 4 * (idx[..., 1] / n - 1))
    r = R_INNER_M + (R_OUTER_M - R_INNER_M) * idx[..., 2] / (2 * layers)
    frames = np.array(FACES, dtype=np.float64)[face]  # (ncells, 3 [n, u, v], 3)
    cube = frames[:, None, 0, :] + a[..., None] * frames[:, None, 1, :] + b[..., None] * frames[:, None, 2, :]
    p = cube * (r / np.linalg.norm(cube, axis=-1))[..., None]
    return p.reshape(-1, 3)


def check_positive_volume(p):
    """Every cell's trilinear map has a positive Jacobian at its centre (VTK's order right-handed)."""
    x = p.reshape(-1, 8, 3)
    d_xi = (x[:, [1, 2, 5, 6]] - x[:, [0, 3, 4, 7]]).sum(1)
    d_eta = (x[:, [3, 2, 7, 6]] - x[:, [0, 1, 4, 5]]).sum(1)
    d_zeta = (x[:, 4:] - x[:, :4]).sum(1)
    det = np.einsum("ij,ij->i", d_xi, np.cross(d_eta, d_zeta))
    if not (det > 0).all():
        sys.exit(f"write_shell.py: {int((det <= 0).sum())} cells with a non-positive Jacobian, expected none")


def blob_centres_m(t_years):
    out = []
    for lat, lon, r_km, amp, sigma in BLOBS:
        la, lo = math.radians(lat), math.radians(lon) + OMEGA_RAD_PER_YEAR * t_years
        r = r_km * 1e3 + U0_M_PER_YEAR * t_years
        out.append(((r * math.cos(la) * math.cos(lo), r * math.cos(la) * math.sin(lo), r * math.sin(la)), amp, sigma))
    return out


def fields(p, t_years):
    radius = np.linalg.norm(p, axis=1)
    blob_sum = np.zeros(len(p))
    for c, amp, sigma_km in blob_centres_m(t_years):
        d2_km = ((p - np.array(c)) ** 2).sum(1) * 1e-6
        blob_sum += amp * np.exp(-d2_km / (2 * sigma_km ** 2))
    velocity = OMEGA_RAD_PER_YEAR * np.column_stack([-p[:, 1], p[:, 0], np.zeros(len(p))]) + U0_M_PER_YEAR * p / radius[:, None]
    depth = R_OUTER_M - radius
    return [("velocity", velocity), ("p", 3300 * 9.81 * depth),
            ("T", 1600 + 2000 * depth / 2886e3 + blob_sum), ("density", 3300 * (1 - 3e-5 * blob_sum))]


def encode(values, dtype, header_type, level):
    """One inline binary DataArray body as VTK writes it with vtkZLibDataCompressor."""
    data = np.ascontiguousarray(values, dtype=dtype).tobytes()
    blocks = [zlib.compress(data[i:i + BLOCK_BYTES], level) for i in range(0, len(data), BLOCK_BYTES)] or [zlib.compress(b"", level)]
    last = len(data) % BLOCK_BYTES
    head = np.array([len(blocks), BLOCK_BYTES, last] + [len(b) for b in blocks], dtype="<u8" if header_type == "UInt64" else "<u4")
    return base64.b64encode(head.tobytes()).decode() + base64.b64encode(b"".join(blocks)).decode()


def data_array(type_name, values, dtype, header_type, level, name=None, components=None):
    attrs = f'type="{type_name}"'
    if name:
        attrs += f' Name="{name}"'
    if components:
        attrs += f' NumberOfComponents="{components}"'
    return f'    <DataArray {attrs} format="binary">\n{encode(values, dtype, header_type, level)}\n    </DataArray>\n'


def write_piece(path, p, t_years, header_type, level):
    ncells = len(p) // 8
    index_type, index_dtype = ("Int64", "<i8") if header_type == "UInt64" else ("Int32", "<i4")
    parts = [
        '<?xml version="1.0"?>\n',
        f'<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" header_type="{header_type}" '
        'compressor="vtkZLibDataCompressor">\n<UnstructuredGrid>\n<FieldData>\n'
        f'  <DataArray type="Float32" Name="TIME" NumberOfTuples="1" format="ascii">{t_years:.9g}</DataArray>\n</FieldData>\n',
        f'<Piece NumberOfPoints="{len(p)}" NumberOfCells="{ncells}">\n  <Points>\n',
        data_array("Float32", p, "<f4", header_type, level, components=3),
        '  </Points>\n  <Cells>\n',
        data_array(index_type, np.arange(len(p)), index_dtype, header_type, level, "connectivity"),
        data_array(index_type, np.arange(1, ncells + 1) * 8, index_dtype, header_type, level, "offsets"),
        data_array("UInt8", np.full(ncells, VTK_HEXAHEDRON), "u1", header_type, level, "types"),
        '  </Cells>\n  <PointData Scalars="T">\n',
    ]
    for name, values in fields(p, t_years):
        parts.append(data_array("Float32", values, "<f4", header_type, level, name, 3 if values.ndim == 2 else None))
    parts.append('  </PointData>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n')
    with open(path, "w") as fh:
        fh.writelines(parts)


def write_record(path, step, pieces):
    lines = ['<?xml version="1.0"?>\n<VTKFile type="PUnstructuredGrid" version="0.1" byte_order="LittleEndian">\n',
             '  <PUnstructuredGrid GhostLevel="0">\n    <PPointData Scalars="T">\n',
             '    <PDataArray type="Float32" Name="velocity" NumberOfComponents="3" format="ascii"/>\n',
             '    <PDataArray type="Float32" Name="p" format="ascii"/>\n',
             '    <PDataArray type="Float32" Name="T" format="ascii"/>\n',
             '    <PDataArray type="Float32" Name="density" format="ascii"/>\n',
             '    </PPointData>\n    <PPoints>\n      <PDataArray type="Float32" NumberOfComponents="3"/>\n    </PPoints>\n']
    lines += [f'    <Piece Source="solution-{step:05d}.{k:04d}.vtu"/>\n' for k in range(pieces)]
    lines.append('  </PUnstructuredGrid>\n</VTKFile>\n')
    with open(path, "w") as fh:
        fh.writelines(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("outdir")
    ap.add_argument("--cells-per-face-edge", type=int, default=96, help="N: columns along a cube face's edge")
    ap.add_argument("--layers", type=int, default=16, help="L: radial layers")
    ap.add_argument("--refine-cap-deg", type=float, default=15.0,
                    help="refine 2x2x2 the columns whose centre is within this angle of +z (0: none)")
    ap.add_argument("--pieces", type=int, default=8, help="P: .vtu files per step")
    ap.add_argument("--steps", type=int, default=1, help="S: time steps, 2 Myr apart")
    ap.add_argument("--header-type", choices=("UInt32", "UInt64"), default="UInt32",
                    help="compression header type; UInt64 also makes connectivity and offsets Int64")
    ap.add_argument("--zlib-level", type=int, default=1, help="zlib level (deal.II's default is best speed, 1)")
    a = ap.parse_args()
    if a.cells_per_face_edge < 1 or a.layers < 1 or a.pieces < 1 or a.steps < 1:
        ap.error("--cells-per-face-edge, --layers, --pieces and --steps must be >= 1")

    start = time.perf_counter()
    rows = cells(a.cells_per_face_edge, a.layers, a.refine_cap_deg)
    ncells = len(rows)
    if a.pieces > ncells:
        ap.error(f"--pieces {a.pieces}: more pieces than the {ncells} cells")
    refined = int((rows[:, 4] == 1).sum())
    out = os.path.abspath(a.outdir)
    parent = os.path.dirname(out)
    os.makedirs(parent, exist_ok=True)
    # Written beside OUTDIR and renamed at the end: never a half-written series under OUTDIR.
    tmp = tempfile.mkdtemp(prefix=".write_shell.", dir=parent)
    try:
        os.makedirs(os.path.join(tmp, "solution"))
        bounds = np.linspace(0, ncells, a.pieces + 1).astype(int)  # equal cell counts, as p4est balances
        nbytes = 0
        for piece in range(a.pieces):
            p = points(rows[bounds[piece]:bounds[piece + 1]], a.cells_per_face_edge, a.layers)
            check_positive_volume(p)
            for step in range(a.steps):
                path = os.path.join(tmp, "solution", f"solution-{step:05d}.{piece:04d}.vtu")
                write_piece(path, p, step * DT_YEARS, a.header_type, a.zlib_level)
                nbytes += os.path.getsize(path)
        for step in range(a.steps):
            write_record(os.path.join(tmp, "solution", f"solution-{step:05d}.pvtu"), step, a.pieces)
        with open(os.path.join(tmp, "solution.pvd"), "w") as fh:
            fh.write('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1" ByteOrder="LittleEndian">\n  <Collection>\n')
            for step in range(a.steps):
                fh.write(f'    <DataSet timestep="{step * DT_YEARS:.17g}" group="" part="0" file="solution/solution-{step:05d}.pvtu"/>\n')
            fh.write('  </Collection>\n</VTKFile>\n')
        truth = {
            "writer": "bench/aspect_resample/write_shell.py (Python + numpy)",
            "layout": "ASPECT visualization output: solution.pvd -> solution/solution-NNNNN.pvtu -> solution-NNNNN.PPPP.vtu",
            "cells": ncells, "points": ncells * 8, "refined_cells": refined, "cells_per_face_edge": a.cells_per_face_edge,
            "layers": a.layers, "refine_cap_deg": a.refine_cap_deg, "pieces": a.pieces, "steps": a.steps,
            "header_type": a.header_type, "inner_radius_m": R_INNER_M, "outer_radius_m": R_OUTER_M,
            "units": {"coordinates": "m", "time": "years", "velocity": "m/year", "p": "Pa", "T": "K", "density": "kg/m^3"},
            "formulas": {
                "blob_sum_K": "sum_i amp_i exp(-|p - c_i(t)|_km^2 / (2 sigma_i^2)); c_i(t): lat_i, lon_i + degrees(omega t), "
                              "r_i [km] + u0 t / 1000 (t in years)",
                "velocity": "omega (-y, x, 0) + u0 p/|p|  (m/year)",
                "p": "3300 * 9.81 * (6371e3 - |p|)",
                "T": "1600 + 2000 (6371e3 - |p|) / 2886e3 + blob_sum",
                "density": "3300 (1 - 3e-5 blob_sum)",
            },
            "omega_rad_per_year": OMEGA_RAD_PER_YEAR, "u0_m_per_year": U0_M_PER_YEAR, "dt_years": DT_YEARS,
            "blobs_lat_lon_rkm_amp_sigma": [list(b) for b in BLOBS],
        }
        with open(os.path.join(tmp, "truth.json"), "w") as fh:
            json.dump(truth, fh, indent=1)
        shutil.rmtree(out, ignore_errors=True)
        os.rename(tmp, out)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    print(f"wrote {out}: {ncells} hexahedra ({refined} of them from refining the {a.refine_cap_deg:g} deg cap), "
          f"{a.pieces} pieces, {a.steps} steps, {nbytes / 1e6:.1f} MB of .vtu in {time.perf_counter() - start:.1f} s")


if __name__ == "__main__":
    main()
