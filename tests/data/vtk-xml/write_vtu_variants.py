#!/usr/bin/python3
"""Writes small VTK XML UnstructuredGrid files in every encoding the VTK file format allows, for the
reader's tests (src/io/vtk_xml_test.cpp), with Python's standard library only (struct, zlib,
base64): a writer independent of RayPC's reader.

    write_vtu_variants.py OUT_DIR

Every variant holds the same mesh: one linear hexahedron, one wedge, one tetrahedron and one
Lagrange hexahedron of degree 2 (27 points), with points repeated per cell as deal.II's DataOut
writes them; point data "f" = x + 2 y + 3 z and a vector "v" = (y, -x, z); FieldData TIME = 1.5e6
and CYCLE = 7. truth.json lists the variants, the cells and the formulas. Also writes a .pvtu
naming two of the variants and a .pvd of two steps, and corrupt files for the error tests.
"""
import base64
import json
import os
import shutil
import struct
import sys
import zlib

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # tests/data
sys.dont_write_bytecode = True  # no __pycache__ in the source tree
from fixture_dir import write_fixture  # noqa: E402

HEX = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]
WEDGE = [(2, 0, 0), (3, 0, 0), (2, 1, 0), (2, 0, 1), (3, 0, 1), (2, 1, 1)]
TETRA = [(4, 0, 0), (5, 0, 0), (4, 1, 0), (4, 0, 1)]


def lagrange_hex_points(origin):
    """The 27 points of a VTK Lagrange hexahedron of degree 2 on a unit cube at `origin`, in VTK's
    order: the 8 corners, the 12 edge midpoints (edges 0-1, 1-2, 3-2, 0-3, 4-5, 5-6, 7-6, 4-7, 0-4,
    1-5, 3-7, 2-6 as VTK numbers them: bottom ring, top ring, verticals 0-4, 1-5, 3-7, 2-6), the
    6 face centres (-x, +x, -y, +y, -z, +z) and the centre."""
    ox, oy, oz = origin
    c = [HEX[i] for i in range(8)]
    mid = lambda a, b: tuple((c[a][k] + c[b][k]) / 2 for k in range(3))
    edges = [(0, 1), (1, 2), (3, 2), (0, 3), (4, 5), (5, 6), (7, 6), (4, 7), (0, 4), (1, 5), (3, 7), (2, 6)]
    faces = [(0, 0.5, 0.5), (1, 0.5, 0.5), (0.5, 0, 0.5), (0.5, 1, 0.5), (0.5, 0.5, 0), (0.5, 0.5, 1)]
    pts = c + [mid(a, b) for a, b in edges] + faces + [(0.5, 0.5, 0.5)]
    return [(ox + x, oy + y, oz + z) for x, y, z in pts]


def mesh():
    cells = [(12, HEX), (13, WEDGE), (10, TETRA), (72, lagrange_hex_points((6, 0, 0)))]
    points, conn, offsets, types = [], [], [], []
    for vtk_type, pts in cells:
        for p in pts:
            conn.append(len(points))
            points.append(p)
        offsets.append(len(conn))
        types.append(vtk_type)
    return points, conn, offsets, types


def f(p):
    return p[0] + 2 * p[1] + 3 * p[2]


def v(p):
    return (p[1], -p[0], p[2])


FORMATS = {"Float32": "f", "Float64": "d", "Int32": "i", "Int64": "q", "UInt8": "B"}


class Encoder:
    def __init__(self, mode, header, compressed, big_endian, float_type):
        self.mode, self.header, self.compressed = mode, header, compressed
        self.endian = ">" if big_endian else "<"
        self.float_type = float_type
        self.appended = b""

    def block(self, type_name, values):
        data = struct.pack(self.endian + FORMATS[type_name] * len(values), *values)
        h = "Q" if self.header == "UInt64" else "I"
        if not self.compressed:
            return [struct.pack(self.endian + h, len(data)), data]
        size = 16  # small blocks, so that arrays span several
        chunks = [data[i:i + size] for i in range(0, len(data), size)] or [b""]
        packed = [zlib.compress(c) for c in chunks]
        last = len(chunks[-1]) if len(chunks[-1]) != size else 0
        head = struct.pack(self.endian + h * (3 + len(packed)), len(packed), size, last, *[len(p) for p in packed])
        return [head, b"".join(packed)]

    def array(self, type_name, values, name=None, components=None):
        attrs = f'type="{type_name}"'
        if name:
            attrs += f' Name="{name}"'
        if components:
            attrs += f' NumberOfComponents="{components}"'
        if self.mode == "ascii":
            text = " ".join(repr(x) for x in values)
            return f'<DataArray {attrs} format="ascii">\n{text}\n</DataArray>\n'
        parts = self.block(type_name, values)
        if self.mode == "binary":
            # header and data encoded apart, as VTK does with a compressor
            text = "".join(base64.b64encode(p).decode() for p in parts)
            return f'<DataArray {attrs} format="binary">\n{text}\n</DataArray>\n'
        offset = len(self.appended)
        if self.mode == "appended-raw":
            self.appended += b"".join(parts)
        else:  # appended-base64: header and data as one base64 stream
            self.appended += base64.b64encode(b"".join(parts))
        return f'<DataArray {attrs} format="appended" offset="{offset}"/>\n'


def write_vtu(path, mode, header="UInt32", compressed=False, big_endian=False, float_type="Float32", time=1.5e6):
    points, conn, offsets, types = mesh()
    e = Encoder(mode, header, compressed, big_endian, float_type)
    flat = [x for p in points for x in p]
    body = ('<FieldData>\n' + e.array("Float64", [time], "TIME").replace("<DataArray", '<DataArray NumberOfTuples="1"', 1)
            + e.array("Int32", [7], "CYCLE").replace("<DataArray", '<DataArray NumberOfTuples="1"', 1) + '</FieldData>\n')
    body += f'<Piece NumberOfPoints="{len(points)}" NumberOfCells="{len(types)}">\n<Points>\n'
    body += e.array(float_type, flat, components=3) + '</Points>\n<Cells>\n'
    body += e.array("Int64", conn, "connectivity") + e.array("Int32", offsets, "offsets") + e.array("UInt8", types, "types")
    body += '</Cells>\n<PointData Scalars="f">\n'
    body += e.array(float_type, [f(p) for p in points], "f")
    body += e.array(float_type, [x for p in points for x in v(p)], "v", 3)
    body += '</PointData>\n</Piece>\n'
    attrs = f'type="UnstructuredGrid" version="1.0" byte_order="{"BigEndian" if big_endian else "LittleEndian"}" header_type="{header}"'
    if compressed:
        attrs += ' compressor="vtkZLibDataCompressor"'
    out = (f'<?xml version="1.0"?>\n<VTKFile {attrs}>\n<UnstructuredGrid>\n{body}</UnstructuredGrid>\n').encode()
    if mode.startswith("appended"):
        enc = "raw" if mode == "appended-raw" else "base64"
        out += f'<AppendedData encoding="{enc}">\n_'.encode() + e.appended + b'\n</AppendedData>\n'
    out += b'</VTKFile>\n'
    with open(path, "wb") as fh:
        fh.write(out)
    return out


def corrupt_first_block(data):
    """`data` with the deflate stream of its first zlib block overwritten (after its 2-byte header)."""
    start = data.index(b"x", data.index(b"_", data.index(b"<AppendedData")) + 1)
    return data[: start + 2] + b"\xff" * 6 + data[start + 8:]


def points_of_mesh():
    return mesh()[0]


def replace_value(data, array_name, index, text):
    """`data` (an ascii .vtu) with value `index` of the DataArray named by `array_name` replaced by `text`."""
    start = data.index(b">", data.index(array_name)) + 1
    end = data.index(b"</DataArray>", start)
    values = data[start:end].split()
    values[index] = text
    return data[:start] + b"\n" + b" ".join(values) + b"\n" + data[end:]


def zero_block_size(data):
    """`data` (appended raw, zlib, UInt32 headers) with the first array's block size set to 0."""
    start = data.index(b"_", data.index(b"<AppendedData")) + 1
    return data[: start + 4] + struct.pack("<I", 0) + data[start + 8:]


def write_variants(tmp):
    """Every file of the fixture, and truth.json, into the folder `tmp`."""
    variants = []
    for mode in ("ascii", "binary", "appended-raw", "appended-base64"):
        for compressed in ((False,) if mode == "ascii" else (False, True)):
            for header in (("UInt32",) if mode == "ascii" else ("UInt32", "UInt64")):
                for float_type in ("Float32", "Float64"):
                    name = f"{mode}-{'zlib' if compressed else 'plain'}-{header}-{float_type}.vtu"
                    write_vtu(os.path.join(tmp, name), mode, header, compressed, False, float_type)
                    variants.append(name)
    write_vtu(os.path.join(tmp, "big-endian-zlib.vtu"), "binary", "UInt32", True, True, "Float64")
    variants.append("big-endian-zlib.vtu")

    # A record of two pieces and a collection of two steps.
    with open(os.path.join(tmp, "record.pvtu"), "w") as fh:
        fh.write('<?xml version="1.0"?>\n<VTKFile type="PUnstructuredGrid" version="0.1" byte_order="LittleEndian">\n'
                 '<PUnstructuredGrid GhostLevel="0">\n<PPointData Scalars="f">\n'
                 '<PDataArray type="Float32" Name="f" format="ascii"/>\n'
                 '<PDataArray type="Float32" Name="v" NumberOfComponents="3" format="ascii"/>\n</PPointData>\n'
                 '<PPoints><PDataArray type="Float32" NumberOfComponents="3"/></PPoints>\n'
                 '<Piece Source="binary-zlib-UInt32-Float32.vtu"/>\n<Piece Source="ascii-plain-UInt32-Float32.vtu"/>\n'
                 '</PUnstructuredGrid>\n</VTKFile>\n')
    with open(os.path.join(tmp, "series.pvd"), "w") as fh:
        fh.write('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1" ByteOrder="LittleEndian">\n<Collection>\n'
                 '<DataSet timestep="0" group="" part="0" file="record.pvtu"/>\n'
                 '<DataSet timestep="2e6" group="" part="0" file="sub/record.pvtu"/>\n</Collection>\n</VTKFile>\n')

    # Corrupt files: each must give one clear error (vtk_xml_test.cpp, VtkXmlBadInput).
    good = open(os.path.join(tmp, "binary-zlib-UInt32-Float32.vtu"), "rb").read()
    raw = open(os.path.join(tmp, "appended-raw-zlib-UInt32-Float32.vtu"), "rb").read()
    bad = {
        "truncated.vtu": raw[: len(raw) * 2 // 3],
        "bad-zlib.vtu": corrupt_first_block(raw),
        "not-xml.vtu": b"this is not XML at all",
        "wrong-type.vtu": good.replace(b'type="UnstructuredGrid"', b'type="PolyData"', 1),
        "bad-cell.vtu": open(os.path.join(tmp, "ascii-plain-UInt32-Float32.vtu"), "rb").read().replace(
            b"12 13 10 72", b"12 13 10 42", 1),
        "bad-index.vtu": open(os.path.join(tmp, "ascii-plain-UInt32-Float32.vtu"), "rb").read().replace(
            b'Name="connectivity" format="ascii">\n0 ', b'Name="connectivity" format="ascii">\n999 ', 1),
        "big-count.vtu": good.replace(b'NumberOfPoints="45"', b'NumberOfPoints="4000000"', 1),
        "count-not-a-number.vtu": good.replace(b'NumberOfPoints="45"', b'NumberOfPoints="abc"', 1),
        "zero-block-size.vtu": zero_block_size(raw),
    }
    # Values a reader must refuse rather than carry on (a NaN crashed `raypc info`): the value 30 of
    # "f" as NaN, the first component of "v" infinite, and a Float64 beyond float32's range.
    ascii64 = open(os.path.join(tmp, "ascii-plain-UInt32-Float64.vtu"), "rb").read()
    bad["nan-value.vtu"] = replace_value(ascii64, b'Name="f"', 30, b"nan")
    bad["inf-value.vtu"] = replace_value(ascii64, b'Name="v"', 0, b"inf")
    bad["huge-value.vtu"] = replace_value(ascii64, b'Name="f"', 3, b"1e39")
    for name, data in bad.items():
        with open(os.path.join(tmp, name), "wb") as fh:
            fh.write(data)
    with open(os.path.join(tmp, "missing-piece.pvd"), "w") as fh:
        fh.write('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1"><Collection>\n'
                 '<DataSet timestep="0" file="nowhere.pvtu"/>\n</Collection>\n</VTKFile>\n')
    with open(os.path.join(tmp, "outside.pvtu"), "w") as fh:
        fh.write('<?xml version="1.0"?>\n<VTKFile type="PUnstructuredGrid" version="0.1" byte_order="LittleEndian">\n'
                 '<PUnstructuredGrid GhostLevel="0">\n<Piece Source="../secret.vtu"/>\n'
                 '</PUnstructuredGrid>\n</VTKFile>\n')
    with open(os.path.join(tmp, "no-timestep.pvd"), "w") as fh:
        fh.write('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1"><Collection>\n'
                 '<DataSet file="record.pvtu"/>\n<DataSet file="sub/record.pvtu"/>\n</Collection>\n</VTKFile>\n')
    with open(os.path.join(tmp, "times-backwards.pvd"), "w") as fh:
        fh.write('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1"><Collection>\n'
                 '<DataSet timestep="5" file="a.pvtu"/>\n<DataSet timestep="1" file="b.pvtu"/>\n</Collection>\n</VTKFile>\n')

    points, conn, offsets, types = mesh()
    truth = {"variants": variants, "points": len(points), "cells": len(types), "types": types, "offsets": offsets,
             "time": 1.5e6, "cycle": 7, "f": "x + 2 y + 3 z", "v": "(y, -x, z)"}
    with open(os.path.join(tmp, "truth.json"), "w") as fh:
        json.dump(truth, fh, indent=1)
    os.makedirs(os.path.join(tmp, "sub"))
    for name in ("record.pvtu", "binary-zlib-UInt32-Float32.vtu", "ascii-plain-UInt32-Float32.vtu"):
        shutil.copyfile(os.path.join(tmp, name), os.path.join(tmp, "sub", name))


def main():
    if len(sys.argv) != 2:
        sys.exit("usage: write_vtu_variants.py OUT_DIR")
    write_fixture(sys.argv[1], write_variants)


if __name__ == "__main__":
    main()
