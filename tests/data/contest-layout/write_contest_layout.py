#!/usr/bin/python3
"""Writes the contest-layout test fixture: three netCDF files in the exact layout of the SciVis 2021
mantle-convection data, with the analytic fields of truth.json (beside this script).

    write_contest_layout.py OUT_DIR

Written with Python's netCDF4 module (Debian's python3-netcdf4) and NumPy, independently of RayPC's
own netCDF code, so that the tests check RayPC's reader against another writer. OUT_DIR receives
spherical001.nc ... spherical003.nc and a copy of truth.json. The files are written into a temporary
folder and moved into place, and not written again when this script and truth.json are unchanged
(a stamp file records their hash), so that every ctest run can ask for them cheaply.
"""
import json
import os
import shutil
import sys

import netCDF4
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # tests/data
sys.dont_write_bytecode = True  # no __pycache__ in the source tree
from fixture_dir import stamp_of, write_fixture  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
SECONDS_PER_MYR = 3.15576e13
R_CMB_KM, R_SURFACE_KM = 3485.0, 6371.0

# (name, units) in the contest files' order; names with spaces as the contest writes them.
VARIABLES = [
    ("temperature", "K"),
    ("vx", "m/s"),
    ("vy", "m/s"),
    ("vz", "m/s"),
    ("thermal conductivity", "W/m/K"),
    ("thermal expansivity", "1/K"),
    ("temperature anomaly", "K"),
    ("spin transition-induced density anomaly", "kg/m^3"),
]


def cartesian_km(lat_deg, lon_deg, r_km):
    lat, lon = np.radians(lat_deg), np.radians(lon_deg)
    return r_km * np.cos(lat) * np.cos(lon), r_km * np.cos(lat) * np.sin(lon), r_km * np.sin(lat)


def fields(truth, lat, r, lon, t_s):
    """Every variable on the (lat, r, lon) grid at time t_s, as truth.json's formulas define them."""
    la, rr, lo = np.meshgrid(lat, r, lon, indexing="ij")
    x, y, z = cartesian_km(la, lo, rr)
    omega, u0 = truth["omega_rad_per_s"], truth["u0_m_per_s"]
    blobs = np.zeros_like(x)
    for lat0, lon0, r0, amp, sigma in truth["blobs_lat_lon_rkm_amp_sigma"]:
        cx, cy, cz = cartesian_km(lat0, lon0 + np.degrees(omega * t_s), r0 + u0 * t_s / 1000.0)
        d2 = (x - cx) ** 2 + (y - cy) ** 2 + (z - cz) ** 2
        blobs += amp * np.exp(-d2 / (2.0 * sigma * sigma))
    anomaly = blobs - blobs.mean(axis=(0, 2), keepdims=True)  # minus its mean over each r shell
    return {
        "temperature": 300.0 + 3700.0 * (R_SURFACE_KM - rr) / (R_SURFACE_KM - R_CMB_KM) + anomaly,
        "vx": omega * -y * 1000.0 + u0 * x / rr,
        "vy": omega * x * 1000.0 + u0 * y / rr,
        "vz": u0 * z / rr,
        "thermal conductivity": -1e-3 * anomaly,
        "thermal expansivity": 1e-8 * anomaly * rr / R_SURFACE_KM,
        "temperature anomaly": anomaly,
        "spin transition-induced density anomaly":
            -0.05 * anomaly * np.exp(-(((R_SURFACE_KM - rr - 1800.0) / 300.0) ** 2)),
    }


def write_step(path, truth, lat, r, lon, t_s):
    with netCDF4.Dataset(path, "w", format="NETCDF3_64BIT_OFFSET") as ds:
        ds.Conventions = "CF-1.6"
        for name, n in (("lat", len(lat)), ("r", len(r)), ("lon", len(lon))):
            ds.createDimension(name, n)
        for name, values, units, long_name in (("lat", lat, "degrees_north", "latitude"),
                                               ("lon", lon, "degrees_east", "longitude"),
                                               ("r", r, "km", "radius")):
            v = ds.createVariable(name, "f8", (name,))
            v.units, v.long_name = units, long_name
            v[:] = values
        values = fields(truth, lat, r, lon, t_s)
        for name, units in VARIABLES:
            v = ds.createVariable(name, "f4", ("lat", "r", "lon"))
            v.units = units
            v[:] = values[name].astype(np.float32)


def main():
    if len(sys.argv) != 2:
        sys.exit("usage: write_contest_layout.py OUT_DIR")
    truth_path = os.path.join(HERE, "truth.json")
    with open(truth_path) as f:
        truth = json.load(f)
    g = truth["grid"]
    if g["style"] != "centred":
        sys.exit(f"{truth_path}: grid style {g['style']!r}: this writer knows 'centred' only")
    step_lat, step_lon = 180.0 / g["nlat"], 360.0 / g["nlon"]
    lat = 90.0 - step_lat / 2 - step_lat * np.arange(g["nlat"])  # cell centres, descending as the contest's
    lon = step_lon * np.arange(g["nlon"])                         # 0 ... 355: the seam not repeated
    r = np.linspace(R_CMB_KM, R_SURFACE_KM, g["nr"])

    def write_all(tmp):
        for k in range(3):
            t_s = k * truth["dt_myr"] * SECONDS_PER_MYR
            write_step(os.path.join(tmp, f"spherical{k + 1:03d}.nc"), truth, lat, r, lon, t_s)
        shutil.copyfile(truth_path, os.path.join(tmp, "truth.json"))

    write_fixture(sys.argv[1], write_all, stamp_of([os.path.abspath(__file__), truth_path]))


if __name__ == "__main__":
    main()
