#!/usr/bin/python3
"""Writes a small global seismic tomography model in the layout of the IRIS Earth Model
Collaboration (EMC) netCDF files, for the tests of opening a model with its own variables
(tests/cli, case `tomography`).

    write_emc_layout.py OUT_DIR [--grid NDEPTHxNLATxNLON]   (the option: bench/open_models.sh)

Written with Python's netCDF4 module (Debian's python3-netcdf4) and NumPy, independently of RayPC's
own netCDF code, following the EMC conventions as its models are published (e.g. S362ANI+M,
GLAD-M25, as EarthScope's emc-tools read them): dimensions `depth`, `latitude`, `longitude`; the
coordinate variables with CF units (`depth` in km, positive down, 50 ... 2850 km; `latitude`
-90 ... 90 in 5 degree steps, the poles included; `longitude` -180 ... 180 in 5 degree steps, the
seam stored twice); one float variable `vs` (depth, latitude, longitude) in km/s with a
`long_name` and a `_FillValue` of 99999, and global attributes as EMC writes them. No
temperature, no velocity of flow: nothing of a mantle-convection model's variables.

    vs = 4.4 + 0.0007 depth + 0.1 cos(lat) cos(lon - 30 deg) (1 - depth / 2891)   [km/s, depth in km]

(the lateral part is largest at the surface and changes sign across the globe; its maximum at
lat 0, lon 30 and its minimum at lat 0, lon -150). truth.json gives the grid and the formula.

Beside it, a regional model as regional tomography is published (e.g. the western United States):
`regional_vs.nc`, latitude 20 ... 55 and longitude -130 ... -65 in 1 degree steps, depth 25 ... 800 km
in 25 km steps, the same formula as `vs`, and no data (the _FillValue) east of -100 degrees below
400 km depth (where such a model's rays do not reach). Nothing of it lies near a pole or the seam.
The file is written into a temporary folder and moved into place, and not written again while this
script is unchanged (a stamp records its hash).
"""
import json
import os
import sys

import netCDF4
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # tests/data
sys.dont_write_bytecode = True  # no __pycache__ in the source tree
from fixture_dir import stamp_of, write_fixture  # noqa: E402

DEPTH_KM = np.linspace(50.0, 2850.0, 15)
LAT_DEG = np.arange(-90.0, 90.0 + 1e-9, 5.0)
LON_DEG = np.arange(-180.0, 180.0 + 1e-9, 5.0)


def vs(depth_km, lat_deg, lon_deg):
    lat = np.radians(lat_deg)
    lon = np.radians(lon_deg - 30.0)
    return 4.4 + 0.0007 * depth_km + 0.1 * np.cos(lat) * np.cos(lon) * (1.0 - depth_km / 2891.0)


def write_coordinates(nc, depth_km, lat_deg, lon_deg):
    """The EMC layout's dimensions and coordinate variables."""
    for name, values in (("depth", depth_km), ("latitude", lat_deg), ("longitude", lon_deg)):
        nc.createDimension(name, len(values))
    d = nc.createVariable("depth", "f4", ("depth",))
    d.long_name, d.units, d.positive = "depth below earth surface", "km", "down"
    d[:] = depth_km
    la = nc.createVariable("latitude", "f4", ("latitude",))
    la.long_name, la.units, la.standard_name = "Latitude; positive north", "degrees_north", "latitude"
    la[:] = lat_deg
    lo = nc.createVariable("longitude", "f4", ("longitude",))
    lo.long_name, lo.units, lo.standard_name = "Longitude; positive east", "degrees_east", "longitude"
    lo[:] = lon_deg


def write(path):
    with netCDF4.Dataset(path, "w", format="NETCDF3_CLASSIC") as nc:
        nc.title = "RayPC test model in the EMC layout (analytic)"
        nc.id = "raypc-emc-test"
        nc.geospatial_lat_min, nc.geospatial_lat_max = -90.0, 90.0
        nc.geospatial_lon_min, nc.geospatial_lon_max = -180.0, 180.0
        nc.geospatial_vertical_min, nc.geospatial_vertical_max = float(DEPTH_KM[0]), float(DEPTH_KM[-1])
        nc.geospatial_vertical_units = "km"
        nc.geospatial_vertical_positive = "down"
        write_coordinates(nc, DEPTH_KM, LAT_DEG, LON_DEG)
        v = nc.createVariable("vs", "f4", ("depth", "latitude", "longitude"), fill_value=99999.0)
        v.long_name, v.display_name, v.units = "Shear-wave velocity", "S Velocity (km/s)", "km/s"
        D, LA, LO = np.meshgrid(DEPTH_KM, LAT_DEG, LON_DEG, indexing="ij")
        v[:] = vs(D, LA, LO).astype(np.float32)


REGIONAL_DEPTH_KM = np.arange(25.0, 800.0 + 1e-9, 25.0)
REGIONAL_LAT_DEG = np.arange(20.0, 55.0 + 1e-9, 1.0)
REGIONAL_LON_DEG = np.arange(-130.0, -65.0 + 1e-9, 1.0)
REGIONAL_FILL = 99999.0


def regional_missing(depth_km, lon_deg):
    """Where the regional model has no data."""
    return (depth_km > 400.0) & (lon_deg > -100.0)


def write_regional(path):
    with netCDF4.Dataset(path, "w", format="NETCDF4") as nc:
        nc.title = "RayPC test model in the EMC layout, regional, with a region of no data (analytic)"
        nc.id = "raypc-emc-regional-test"
        nc.geospatial_lat_min, nc.geospatial_lat_max = 20.0, 55.0
        nc.geospatial_lon_min, nc.geospatial_lon_max = -130.0, -65.0
        nc.geospatial_vertical_units = "km"
        nc.geospatial_vertical_positive = "down"
        write_coordinates(nc, REGIONAL_DEPTH_KM, REGIONAL_LAT_DEG, REGIONAL_LON_DEG)
        v = nc.createVariable("vs", "f4", ("depth", "latitude", "longitude"), fill_value=REGIONAL_FILL)
        v.long_name, v.units = "Shear-wave velocity", "km/s"
        D, LA, LO = np.meshgrid(REGIONAL_DEPTH_KM, REGIONAL_LAT_DEG, REGIONAL_LON_DEG, indexing="ij")
        values = vs(D, LA, LO).astype(np.float32)
        values[regional_missing(D, LO)] = REGIONAL_FILL
        v.set_auto_mask(False)
        v[:] = values


def main():
    global DEPTH_KM, LAT_DEG, LON_DEG
    args = sys.argv[1:]
    if "--grid" in args:
        nd, nla, nlo = (int(n) for n in args[args.index("--grid") + 1].split("x"))
        DEPTH_KM = np.linspace(50.0, 2850.0, nd)
        LAT_DEG = np.linspace(-90.0, 90.0, nla)
        LON_DEG = np.linspace(-180.0, 180.0, nlo)
        del args[args.index("--grid"):args.index("--grid") + 2]
    if len(args) != 1:
        sys.exit("usage: write_emc_layout.py OUT_DIR [--grid NDEPTHxNLATxNLON]")

    def write_all(tmp):
        write(os.path.join(tmp, "global_vs.nc"))
        truth = {"file": "global_vs.nc", "variable": "vs", "units": "km/s", "depth_km": DEPTH_KM.tolist(),
                 "lat_deg": LAT_DEG.tolist(), "lon_deg": LON_DEG.tolist(),
                 "vs": "4.4 + 0.0007 depth + 0.1 cos(lat) cos(lon - 30 deg) (1 - depth / 2891)"}
        write_regional(os.path.join(tmp, "regional_vs.nc"))
        truth["regional"] = {"file": "regional_vs.nc", "depth_km": REGIONAL_DEPTH_KM.tolist(),
                             "lat_deg": REGIONAL_LAT_DEG.tolist(), "lon_deg": REGIONAL_LON_DEG.tolist(),
                             "fill_value": REGIONAL_FILL,
                             "missing": "depth > 400 km and lon > -100 deg"}
        with open(os.path.join(tmp, "truth.json"), "w") as fh:
            json.dump(truth, fh, indent=1)

    write_fixture(args[0], write_all, stamp_of([os.path.abspath(__file__)], " ".join(sys.argv[2:])))


if __name__ == "__main__":
    main()
