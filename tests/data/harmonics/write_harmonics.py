#!/usr/bin/python3
"""Writes fields of known spherical harmonics on a lat x r x lon grid, for the truth tests of
`raypc correlate` and `raypc spectrum` (tests/cli, case `compare_sphere`; tests/python/test_compare.py).

    write_harmonics.py OUT_DIR

Written with Python's netCDF4 module (Debian's python3-netcdf4) and NumPy, independently of RayPC and
of libsharp: the associated Legendre functions come from their three-term recurrence here. The
harmonics are the 4π-normalised real ones,

    Y(l, m)(lat, lon) = sqrt((2 - δ_m0) (2l + 1) (l - m)! / (l + m)!) P_lm(sin lat) cos(m lon)

(1/4π ∫ Y² dΩ = 1), so that a field A Y(l, m) has the power A² at degree l and none elsewhere, and its
RMS over the sphere is A. On every shell the amplitude is A(r) = r / 1000 km.

`global.nc`: dimensions (lat, r, lon), lat the cell centres -89 ... 89 (2 degree steps, no pole
rows: Fejér's first rule), r 3500 ... 6300 km in 5 shells, lon 0 ... 358 (2 degree steps); float
variables (no units: amplitudes):
    y20            A Y(2, 0)
    y20_negative   -A Y(2, 0)
    y31            A Y(3, 1)
    mix            A (Y(2, 0) + 0.5 Y(5, 3) + 0.25 Y(9, 0))
    mix_turned     mix turned by 180 degrees in longitude (Y(5, 3) changes sign)
    y20_holes      y20 with no data (the _FillValue) north of 60 degrees on the two deepest shells
`poles.nc`: the same y20 and y31 on lat -90 ... 90 (2 degree steps, both poles: Clenshaw–Curtis).
`regional.nc`: y20 on lat 20 ... 60, lon 200 ... 300 (2 degree steps), the same radii: a regional grid.
truth.json gives the grids, the amplitudes and the formulas. The folder is written whole, and not again
while this script is unchanged (a stamp records its hash).
"""
import json
import math
import os
import sys

import netCDF4
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # tests/data
sys.dont_write_bytecode = True  # no __pycache__ in the source tree
from fixture_dir import stamp_of, write_fixture  # noqa: E402

R_KM = np.linspace(3500.0, 6300.0, 5)
FILL = 9.96921e36


def legendre(l, m, x):
    """P_lm(x) without the Condon-Shortley phase, by the recurrence in l from P_mm."""
    pmm = np.ones_like(x)
    s = np.sqrt(np.maximum(0.0, 1.0 - x * x))
    for k in range(1, m + 1):
        pmm = pmm * (2 * k - 1) * s
    if l == m:
        return pmm
    pm1 = x * (2 * m + 1) * pmm
    if l == m + 1:
        return pm1
    for ll in range(m + 2, l + 1):
        pmm, pm1 = pm1, ((2 * ll - 1) * x * pm1 - (ll + m - 1) * pmm) / (ll - m)
    return pm1


def ybar(l, m, lat_deg, lon_deg):
    norm = math.sqrt((1 if m == 0 else 2) * (2 * l + 1) * math.factorial(l - m) / math.factorial(l + m))
    return norm * legendre(l, m, np.sin(np.radians(lat_deg))) * np.cos(m * np.radians(lon_deg))


def amplitude(r_km):
    return r_km / 1000.0


def fields(lat, lon):
    """Every variable on (lat, r, lon)."""
    LA, R, LO = np.meshgrid(lat, R_KM, lon, indexing="ij")
    a = amplitude(R)
    mix = lambda lo: a * (ybar(2, 0, LA, lo) + 0.5 * ybar(5, 3, LA, lo) + 0.25 * ybar(9, 0, LA, lo))  # noqa: E731
    y20 = a * ybar(2, 0, LA, LO)
    holes = y20.copy()
    holes[(LA > 60.0) & (R < R_KM[2])] = FILL
    return {"y20": y20, "y20_negative": -y20, "y31": a * ybar(3, 1, LA, LO), "mix": mix(LO),
            "mix_turned": mix(LO + 180.0), "y20_holes": holes}


def write(path, lat, lon, names):
    with netCDF4.Dataset(path, "w", format="NETCDF4") as nc:
        nc.title = "Spherical harmonics for RayPC's truth tests (analytic)"
        for name, values in (("lat", lat), ("r", R_KM), ("lon", lon)):
            nc.createDimension(name, len(values))
        la = nc.createVariable("lat", "f8", ("lat",))
        la.units, la.standard_name = "degrees_north", "latitude"
        la[:] = lat
        r = nc.createVariable("r", "f8", ("r",))
        r.units, r.long_name = "km", "radius"
        r[:] = R_KM
        lo = nc.createVariable("lon", "f8", ("lon",))
        lo.units, lo.standard_name = "degrees_east", "longitude"
        lo[:] = lon
        values = fields(lat, lon)
        for name in names:
            v = nc.createVariable(name, "f4", ("lat", "r", "lon"), fill_value=np.float32(FILL))
            v.long_name = name
            v.set_auto_mask(False)
            v[:] = values[name].astype(np.float32)


def main():
    if len(sys.argv) != 2:
        sys.exit("usage: write_harmonics.py OUT_DIR")
    centred = np.arange(-89.0, 89.0 + 1e-9, 2.0)
    poles = np.arange(-90.0, 90.0 + 1e-9, 2.0)
    lon = np.arange(0.0, 358.0 + 1e-9, 2.0)

    def write_all(tmp):
        write(os.path.join(tmp, "global.nc"), centred, lon, ["y20", "y20_negative", "y31", "mix", "mix_turned", "y20_holes"])
        write(os.path.join(tmp, "poles.nc"), poles, lon, ["y20", "y31"])
        write(os.path.join(tmp, "regional.nc"), np.arange(20.0, 60.0 + 1e-9, 2.0), np.arange(200.0, 300.0 + 1e-9, 2.0),
              ["y20"])
        truth = {"r_km": R_KM.tolist(), "amplitude": [amplitude(r) for r in R_KM],
                 "harmonics": "sqrt((2 - d_m0)(2l + 1)(l - m)!/(l + m)!) P_lm(sin lat) cos(m lon), times r / 1000 km",
                 "global": {"lat_deg": centred.tolist(), "lon_deg": lon.tolist()},
                 "poles": {"lat_deg": poles.tolist()},
                 "mix": {"2": 1.0, "5": 0.25, "9": 0.0625},
                 "holes": "y20_holes: none north of 60 deg on the shells r < 4900 km",
                 "regional": {"lat_deg": [20, 60], "lon_deg": [200, 300]}}
        with open(os.path.join(tmp, "truth.json"), "w") as fh:
            json.dump(truth, fh, indent=1)

    write_fixture(sys.argv[1], write_all, stamp_of([os.path.abspath(__file__)]))


if __name__ == "__main__":
    main()
