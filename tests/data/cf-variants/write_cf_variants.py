#!/usr/bin/python3
"""Writes small netCDF files that hold one analytic mantle field in the shapes CF-conforming models
and tomography tools write, for the reader's tests CfVariants.* in
src/io/netcdf_reader_test.cpp.

    write_cf_variants.py OUT_DIR

Written with Python's netCDF4 module (Debian's python3-netcdf4) and NumPy, independently of RayPC's
own netCDF code. Every file holds the same 12 x 9 x 16 grid (lat x r x lon: cell-centred lat rows,
radius 3485 ... 6371 km, lon every 22.5 degrees) and the fields

    temperature = 300 + 3700 (6371 - r) / 2886 + 150 sin(lat) + 100 cos(lat) sin(lon + 20 deg)  [K]
    vx          = 1e-9 cos(lat) sin(lon) r / 6371                                                [m/s]

(odd in lat and in lon, so that a mirrored axis shows), stored as each variant says: a time
dimension, other names found by CF attributes, other units of the coordinates, depth instead of
radius, double values with huge fill values, packed unsigned shorts, NC_STRING attributes.
OUT_DIR/truth.json gives the expected grid (canonical: lat and lon in degrees, ascending, lon in
[0, 360); r in km, ascending) and values (canonical order: lat, r, lon, lon fastest), and for every
variant the file, the reader options a test passes and either a tolerance (and the values where they
differ from the truth's: fill values replaced, packing) or the facts a refusal must name. The files are written into a temporary folder and moved into
place, and not written again while this script is unchanged (a stamp records its hash).
"""
import json
import os
import sys

import netCDF4
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # tests/data
sys.dont_write_bytecode = True  # no __pycache__ in the source tree
from fixture_dir import stamp_of, write_fixture  # noqa: E402

R_CMB_KM, R_SURFACE_KM = 3485.0, 6371.0
NLAT, NR, NLON = 12, 9, 16
LAT_DEG = -90.0 + (np.arange(NLAT) + 0.5) * 180.0 / NLAT
R_KM = np.linspace(R_CMB_KM, R_SURFACE_KM, NR)
LON_DEG = np.arange(NLON) * 360.0 / NLON
UNITS = {"temperature": "K", "vx": "m/s"}


def fields(lat_deg, r_km, lon_deg):
    """The analytic fields on the grid of the given axes, indexed [lat, r, lon]."""
    la, rr, lo = np.meshgrid(np.radians(lat_deg), r_km, np.radians(lon_deg), indexing="ij")
    return {
        "temperature": 300.0 + 3700.0 * (R_SURFACE_KM - rr) / (R_SURFACE_KM - R_CMB_KM) + 150.0 * np.sin(la)
        + 100.0 * np.cos(la) * np.sin(lo + np.radians(20.0)),
        "vx": 1e-9 * np.cos(la) * np.sin(lo) * rr / R_SURFACE_KM,
    }


TRUTH = fields(LAT_DEG, R_KM, LON_DEG)


class Layout:
    """How one file stores the canonical grid: names, dims order, coordinate values and attributes."""

    def __init__(self, **kw):
        self.fmt = kw.get("fmt", "NETCDF3_64BIT_OFFSET")
        self.names = kw.get("names", {"lat": "lat", "r": "r", "lon": "lon"})
        self.order = kw.get("order", ("lat", "r", "lon"))  # the variables' grid dims, slowest first
        # Coordinate values as stored, from the canonical ones (degrees, km).
        self.lat = kw.get("lat", lambda v: v)
        self.r = kw.get("r", lambda v: v)
        self.lon = kw.get("lon", lambda v: v)
        self.flip = kw.get("flip", ())  # axes stored in descending order
        self.attrs = {"lat": {"units": "degrees_north"}, "r": {"units": "km"}, "lon": {"units": "degrees_east"}}
        for axis, attrs in kw.get("attrs", {}).items():
            self.attrs[axis] = attrs
        self.string_attrs = kw.get("string_attrs", False)  # every text attribute as NC_STRING
        self.time = kw.get("time")  # None, or (length, unlimited)
        self.types = kw.get("types", {"temperature": "f4", "vx": "f4"})
        self.var_names = kw.get("var_names", {})
        self.compress = kw.get("compress", False)


def set_text(var, name, value, as_string):
    if as_string:
        var.setncattr_string(name, value)
    else:
        var.setncattr(name, value)


def write(path, layout, values=None, edit=None, skip=(), extra=None):
    """Writes `values` (canonical [lat, r, lon] arrays, default TRUTH) in `layout`, but not the variables
    in `skip`. `edit(name)` may return attributes of a variable, its fill_value and a function `data`
    from its canonical values to the numbers stored. `extra(ds)` may add variables."""
    values = TRUTH if values is None else values
    index = {"lat": np.arange(NLAT), "r": np.arange(NR), "lon": np.arange(NLON)}
    for axis in layout.flip:
        index[axis] = index[axis][::-1]
    canonical = {"lat": LAT_DEG, "r": R_KM, "lon": LON_DEG}
    stored = {"lat": layout.lat, "r": layout.r, "lon": layout.lon}
    with netCDF4.Dataset(path, "w", format=layout.fmt) as ds:
        set_text(ds, "Conventions", "CF-1.8", layout.string_attrs)
        dims = []
        if layout.time:
            length, unlimited = layout.time
            ds.createDimension("time", None if unlimited else length)
            t = ds.createVariable("time", "f8", ("time",))
            for k, v in (("units", "days since 2000-01-01 00:00:00"), ("standard_name", "time"), ("axis", "T"),
                         ("calendar", "standard")):
                set_text(t, k, v, layout.string_attrs)
            t[:] = 365.25 * np.arange(length)
            dims.append("time")
        for axis in ("lat", "r", "lon"):
            name = layout.names[axis]
            ds.createDimension(name, len(canonical[axis]))
            v = ds.createVariable(name, "f8", (name,))
            for k, a in layout.attrs[axis].items():
                set_text(v, k, a, layout.string_attrs)
            v[:] = stored[axis](canonical[axis][index[axis]])
        if extra:
            extra(ds)
        dims += [layout.names[a] for a in layout.order]
        axes = {"lat": 0, "r": 1, "lon": 2}
        for name in ("temperature", "vx"):
            if name in skip:
                continue
            extra = dict(edit(name)) if edit else {}
            data = values[name]
            if "data" in extra:
                data = extra.pop("data")(data)  # canonical [lat, r, lon] in, stored numbers out
            data = data[np.ix_(index["lat"], index["r"], index["lon"])]
            data = np.transpose(data, [axes[a] for a in layout.order])
            if layout.time:
                # Step k holds the values + 100 k (in stored numbers), so that a reader that takes
                # the wrong step shows.
                data = np.stack([data + 100.0 * k for k in range(layout.time[0])])
            file_name = layout.var_names.get(name, name)
            var_type = layout.types[name]
            kwargs = {"zlib": True, "complevel": 4} if layout.compress else {}
            if "fill_value" in extra:
                kwargs["fill_value"] = extra.pop("fill_value")
            v = ds.createVariable(file_name, var_type, dims, **kwargs)
            v.set_auto_maskandscale(False)
            set_text(v, "units", UNITS[name], layout.string_attrs)
            for k, a in extra.items():
                if isinstance(a, str):
                    set_text(v, k, a, layout.string_attrs)
                else:
                    v.setncattr(k, a)
            v[:] = np.asarray(data).astype(var_type)


def accepted(file, tolerance=None, values=None, **options):
    """A variant the reader must read: its truth is the canonical grid and `values`."""
    tolerance = tolerance or {}
    entry = {"file": file, "units": UNITS, "tolerance": {}}
    if values is not None:  # else the truth's "values"
        entry["values"] = {name: v.ravel().tolist() for name, v in values.items()}
    for name in ("temperature", "vx"):
        # float32 storage: a few ulps of the largest value
        entry["tolerance"][name] = tolerance.get(name, 4e-7 * float(np.abs(TRUTH[name]).max()))
    entry["options"] = options
    return entry


def point(ilat, ir, ilon):
    return {"lat_deg": LAT_DEG[ilat], "r_km": R_KM[ir], "lon_deg": LON_DEG[ilon], "index": [ilat, ir, ilon]}


def shell_filled(values, cells):
    """`values` with each of `cells` replaced by the mean of the other values of its radius shell, as
    --fill-missing does."""
    out = values.copy()
    for ilat, ir, ilon in cells:
        shell = values[:, ir, :].copy()
        mask = np.ones(shell.shape, bool)
        for a, b, c in cells:
            if b == ir:
                mask[a, c] = False
        out[ilat, ir, ilon] = shell[mask].mean()
    return out


def write_variants(out):
    truth = {"lat_deg": LAT_DEG.tolist(), "r_km": R_KM.tolist(), "lon_deg": LON_DEG.tolist(),
             "values": {name: v.ravel().tolist() for name, v in TRUTH.items()}, "formulas": __doc__,
             "variants": {}}
    variants = truth["variants"]

    # 1. A leading time dimension of length 1, fixed (netCDF-4 classic model) or unlimited (a record
    # dimension of a 64-bit-offset file; and a compressed netCDF-4 file).
    write(os.path.join(out, "time_fixed.nc"), Layout(fmt="NETCDF4_CLASSIC", time=(1, False)))
    variants["time_fixed"] = accepted("time_fixed.nc")
    write(os.path.join(out, "time_unlimited.nc"), Layout(time=(1, True)))
    variants["time_unlimited"] = accepted("time_unlimited.nc")
    write(os.path.join(out, "time_unlimited_nc4.nc"),
          Layout(fmt="NETCDF4", time=(1, True), compress=True, order=("lon", "lat", "r"), flip=("lat",)))
    variants["time_unlimited_nc4"] = accepted("time_unlimited_nc4.nc")
    # Three steps in one file: refused, naming the dimension and its length.
    write(os.path.join(out, "time_three_steps.nc"), Layout(time=(3, True)))
    variants["time_three_steps"] = {"file": "time_three_steps.nc", "dimension": "time", "length": 3,
                                    "step_offset": 100.0}

    # 2. Doubles: a _FillValue of 1e300 in three cells (read with --fill-missing: the shell's mean), and
    # a value of 1e39, beyond float32, in one cell.
    fill_cells = [(2, 3, 5), (7, 3, 11), (10, 6, 0)]

    def fill_1e300(name):
        if name != "temperature":
            return {}

        def put(d):
            d = np.array(d, dtype="f8")
            for ilat, ir, ilon in fill_cells:
                d[ilat, ir, ilon] = 1e300
            return d
        return {"fill_value": 1e300, "data": put}
    double_layout = Layout(fmt="NETCDF4", types={"temperature": "f8", "vx": "f8"})
    write(os.path.join(out, "double_fill_1e300.nc"), double_layout, edit=fill_1e300)
    filled = dict(TRUTH, temperature=shell_filled(TRUTH["temperature"], fill_cells))
    variants["double_fill_1e300"] = accepted("double_fill_1e300.nc", values=filled, fill_missing=True,
                                             tolerance={"temperature": 1e-3})
    variants["double_fill_1e300"]["fill"] = {"value": 1e300, "count": len(fill_cells),
                                             "first": point(*min(fill_cells))}

    beyond_cell = (4, 5, 9)

    def beyond_float(name):
        if name != "temperature":
            return {}

        def put(d):
            d = np.array(d, dtype="f8")
            d[beyond_cell] = 1e39
            return d
        return {"data": put}
    write(os.path.join(out, "double_beyond_float.nc"), double_layout, edit=beyond_float)
    variants["double_beyond_float"] = {"file": "double_beyond_float.nc", "value": 1e39,
                                       "at": point(*beyond_cell)}

    # 3. Units. Radius in metres, every text attribute an NC_STRING (netCDF-4 writes those).
    write(os.path.join(out, "radius_m_string_units.nc"),
          Layout(fmt="NETCDF4", r=lambda v: v * 1000.0, attrs={"r": {"units": "m"}}, string_attrs=True))
    variants["radius_m_string_units"] = accepted("radius_m_string_units.nc")
    # Radius in metres, in km and non-dimensional (a fraction of 6371 km), without units: metres and
    # fractions are refused unless an option says what they are; km fit a mantle and are read.
    write(os.path.join(out, "radius_m_no_units.nc"), Layout(r=lambda v: v * 1000.0, attrs={"r": {}}))
    variants["radius_m_no_units"] = accepted("radius_m_no_units.nc", radius_units="m")
    variants["radius_m_no_units"]["stored_range"] = [R_CMB_KM * 1000.0, R_SURFACE_KM * 1000.0]
    write(os.path.join(out, "radius_nondimensional.nc"),
          Layout(r=lambda v: v / R_SURFACE_KM, attrs={"r": {"long_name": "radius / Earth's radius"}}))
    variants["radius_nondimensional"] = accepted("radius_nondimensional.nc", radius_units="nondimensional")
    variants["radius_nondimensional"]["stored_range"] = [R_CMB_KM / R_SURFACE_KM, 1.0]
    write(os.path.join(out, "radius_km_no_units.nc"), Layout(attrs={"r": {}}))
    variants["radius_km_no_units"] = accepted("radius_km_no_units.nc")
    write(os.path.join(out, "radius_unknown_units.nc"),
          Layout(r=lambda v: v / 1.609344, attrs={"r": {"units": "miles"}}))
    variants["radius_unknown_units"] = {"file": "radius_unknown_units.nc", "units": "miles"}

    # Latitude and longitude in radians; latitude in radians without units (refused).
    write(os.path.join(out, "angles_radians.nc"),
          Layout(lat=np.radians, lon=np.radians, flip=("lat",),
                 attrs={"lat": {"units": "radians"}, "lon": {"units": "radian"}}))
    variants["angles_radians"] = accepted("angles_radians.nc")
    write(os.path.join(out, "lat_radians_no_units.nc"), Layout(lat=np.radians, attrs={"lat": {}}))
    variants["lat_radians_no_units"] = {"file": "lat_radians_no_units.nc"}

    # degrees_south and degrees_west: the stored numbers are the negated latitude and longitude.
    write(os.path.join(out, "lat_degrees_south.nc"),
          Layout(lat=lambda v: -v, attrs={"lat": {"units": "degrees_south"}}))
    variants["lat_degrees_south"] = accepted("lat_degrees_south.nc")
    write(os.path.join(out, "lon_degrees_west.nc"),
          Layout(lon=lambda v: -v, attrs={"lon": {"units": "degrees_west"}}))
    variants["lon_degrees_west"] = accepted("lon_degrees_west.nc")

    # Packed unsigned shorts: temperature = 0.07 * (unsigned raw), raw 1717 ... 59712, so that read as
    # signed shorts the values above 2293 K turn negative. _FillValue 65535 (stored as -1) in one cell.
    scale = float(np.float32(0.07))
    unsigned_fill_cell = (5, 8, 3)
    packed = np.round(TRUTH["temperature"] / scale)
    unpacked = packed * scale

    def unsigned_short(name):
        if name != "temperature":
            return {}

        def put(d):
            raw = np.round(np.asarray(d) / scale)
            assert raw.min() >= 0 and raw.max() < 65535
            raw = raw.astype(np.uint16)
            raw[unsigned_fill_cell] = 65535
            return raw.view(np.int16)
        return {"fill_value": np.int16(-1), "_Unsigned": "true", "scale_factor": np.float32(scale),
                "add_offset": np.float32(0.0), "data": put}
    write(os.path.join(out, "unsigned_short.nc"), Layout(fmt="NETCDF4_CLASSIC", types={"temperature": "i2",
                                                                                       "vx": "f4"}),
          edit=unsigned_short)
    values = dict(TRUTH, temperature=shell_filled(unpacked, [unsigned_fill_cell]))
    variants["unsigned_short"] = accepted("unsigned_short.nc", values=values, fill_missing=True,
                                          tolerance={"temperature": 1e-3})
    variants["unsigned_short"]["packed_range"] = [float(packed.min()), float(packed.max())]

    # Depth (positive down) instead of radius: depth = 6371 km - r, in km named "depth", and in metres
    # under a name no list holds, found by its CF attributes (axis Z, positive down).
    write(os.path.join(out, "depth_km.nc"),
          Layout(names={"lat": "lat", "r": "depth", "lon": "lon"}, r=lambda v: R_SURFACE_KM - v,
                 order=("lon", "r", "lat"),
                 attrs={"r": {"units": "km", "positive": "down", "standard_name": "depth"}}))
    variants["depth_km"] = accepted("depth_km.nc")
    write(os.path.join(out, "depth_m_cf.nc"),
          Layout(fmt="NETCDF4", names={"lat": "lat", "r": "zc", "lon": "lon"},
                 r=lambda v: (R_SURFACE_KM - v) * 1000.0, order=("r", "lat", "lon"), flip=("r",),
                 attrs={"r": {"units": "m", "positive": "down", "axis": "Z"}}))
    variants["depth_m_cf"] = accepted("depth_m_cf.nc")

    # Names no list holds, found by standard_name (lat), axis (lon, whose units say only "degrees")
    # and axis with positive up (radius); variables mapped by name.
    write(os.path.join(out, "cf_names.nc"),
          Layout(fmt="NETCDF4", names={"lat": "phi", "r": "rho", "lon": "lam"}, order=("r", "lon", "lat"),
                 attrs={"lat": {"standard_name": "latitude", "units": "degree_north"},
                        "r": {"units": "kilometre", "axis": "Z", "positive": "up"},
                        "lon": {"units": "degrees", "axis": "X"}},
                 var_names={"temperature": "T", "vx": "u_east"}))
    variants["cf_names"] = accepted("cf_names.nc", map={"temperature": "T", "vx": "u_east"})

    # Several variables with CF attributes of latitude: a staggered coordinate variable on a dim the
    # data do not use (lat_u, cell edges) is not the data's; two auxiliary variables on the data's dim,
    # neither named as a coordinate, are refused unless an option names one.
    def lat_edges(ds):
        ds.createDimension("lat_u", NLAT + 1)
        v = ds.createVariable("lat_u", "f8", ("lat_u",))
        v.units = "degrees_north"
        v[:] = np.linspace(-90.0, 90.0, NLAT + 1)
    write(os.path.join(out, "staggered_lat.nc"), Layout(), extra=lat_edges)
    variants["staggered_lat"] = accepted("staggered_lat.nc")

    def two_lats(ds):
        for name in ("lat_a", "lat_b"):
            v = ds.createVariable(name, "f8", ("y",))
            v.units = "degrees_north"
            v[:] = LAT_DEG
    write(os.path.join(out, "ambiguous_lat.nc"),
          Layout(names={"lat": "y", "r": "r", "lon": "lon"}, attrs={"lat": {"long_name": "row"}}), extra=two_lats)
    variants["ambiguous_lat"] = accepted("ambiguous_lat.nc", lat_name="lat_b")
    variants["ambiguous_lat"]["claimants"] = ["lat_a", "lat_b"]

    # 4. Two-step series with a time dimension: vx missing in the second step; a grid that differs.
    for series in ("series_missing_variable", "series_grid_differs"):
        os.makedirs(os.path.join(out, series))
    layout = Layout(time=(1, True))
    write(os.path.join(out, "series_missing_variable", "step1.nc"), layout)
    write(os.path.join(out, "series_missing_variable", "step2.nc"), layout, skip=("vx",))
    variants["series_missing_variable"] = {"files": ["series_missing_variable/step1.nc",
                                                     "series_missing_variable/step2.nc"],
                                           "missing": "vx", "in": "step2.nc"}
    write(os.path.join(out, "series_grid_differs", "step1.nc"), layout)
    write(os.path.join(out, "series_grid_differs", "step2.nc"),
          Layout(time=(1, True), r=lambda v: v * 1000.0, attrs={"r": {"units": "m"}}))
    shifted = Layout(time=(1, True), lat=lambda v: v + 1.0)
    write(os.path.join(out, "series_grid_differs", "step3.nc"), shifted)
    variants["series_grid_differs"] = {"files": ["series_grid_differs/step1.nc", "series_grid_differs/step2.nc",
                                                 "series_grid_differs/step3.nc"],
                                       "differs": "step3.nc"}
    return truth


def main():
    if len(sys.argv) != 2:
        sys.exit("usage: write_cf_variants.py OUT_DIR")

    def write_all(tmp):
        truth = write_variants(tmp)
        with open(os.path.join(tmp, "truth.json"), "w") as f:
            json.dump(truth, f)

    write_fixture(sys.argv[1], write_all, stamp_of([os.path.abspath(__file__)]))


if __name__ == "__main__":
    main()
