"""Two fields compared on the sphere (docs/compare.md): the correlation per depth, the spherical-harmonic
power per degree and depth, and the per-degree correlation at a depth, as xarray objects on CF
coordinates. Each is computed by the code of ``raypc correlate`` and ``raypc spectrum`` (the compiled
module's binding of app/compare_fields.h), so that the numbers equal the CLI's CSV."""
from __future__ import annotations

import os
from typing import TYPE_CHECKING, Optional, Union

import numpy as np

from . import _raypc

if TYPE_CHECKING:
    import xarray as xr

    from .dataset import Dataset

FieldInput = Union["Dataset", str, os.PathLike]  # a Dataset, a dataset directory or inputs raypc serve takes


def _input(x: FieldInput) -> str:
    path = getattr(x, "path", None)
    return os.fspath(path if path is not None and not isinstance(x, (str, os.PathLike)) else x)


def _step(step) -> str:
    return str(step)


def _lmax(lmax: Optional[int]) -> int:
    if lmax is None:
        return -1
    if isinstance(lmax, bool) or not isinstance(lmax, (int, np.integer)) or lmax < 0:
        raise _raypc.Error(f"lmax: {lmax!r}, expected a spherical-harmonic degree, 0 or more (or None)")
    return int(lmax)


def _depth_coord(depth_km: np.ndarray, radius_km: np.ndarray) -> dict:
    return {"depth": ("depth", depth_km, {"units": "km", "positive": "down", "standard_name": "depth",
                                          "long_name": "depth below the surface", "axis": "Z"}),
            "radius": ("depth", radius_km, {"units": "km", "long_name": "radius"})}


def _field_attrs(prefix: str, f: dict) -> dict:
    return {f"{prefix}title": f["title"], f"{prefix}variable": f["variable"], f"{prefix}units": f["units"],
            f"{prefix}dataset": f["dataset"], f"{prefix}step": f["step"], f"{prefix}time_myr": f["time_myr"]}


def correlate(a: FieldInput, b: FieldInput, var_a: Optional[str] = None, var_b: Optional[str] = None,
              lmax: Optional[int] = None, step=0, step_b=None) -> "xr.Dataset":
    """The area-weighted Pearson correlation of two fields per depth (each radius shell of ``a``'s grid),
    the RMS of each about the shell's mean and their ratio, the points and area both cover: ``raypc
    correlate A[:VAR] B[:VAR] [--lmax L] [--time STEP] [--time-b STEP_B]``'s table as an xarray.Dataset on a
    CF ``depth`` coordinate (km, positive down). ``lmax``: both filtered to degree <= lmax first. ``step``
    (an index or "24Myr") is ``b``'s too unless ``step_b`` is given. ``b`` is resampled onto ``a``'s grid
    when the grids differ. NaN where a value cannot be made; the ``note`` variable says why."""
    import xarray as xr

    d = _raypc.correlate(_input(a), var_a or "", _step(step), _input(b), var_b or "",
                         _step(step if step_b is None else step_b), _lmax(lmax))
    ua, ub = d["a"]["units"] or "1", d["b"]["units"] or "1"
    data = {
        "correlation": ("depth", d["correlation"], {"units": "1", "long_name": "area-weighted Pearson correlation of a and b"}),
        "rms_a": ("depth", d["rms_a"], {"units": ua, "long_name": f"RMS of {d['a']['variable']} about the shell's mean"}),
        "rms_b": ("depth", d["rms_b"], {"units": ub, "long_name": f"RMS of {d['b']['variable']} about the shell's mean"}),
        "rms_ratio": ("depth", d["rms_ratio"], {"units": "1" if ua == ub else f"({ua})/({ub})", "long_name": "rms_a / rms_b"}),
        "points": ("depth", d["points"], {"long_name": "grid points where both have data"}),
        "area_covered_percent": ("depth", d["area_covered_percent"],
                                 {"units": "%", "long_name": "their area, percent of the sphere"}),
        "note": ("depth", np.array(d["note"], dtype=object), {"long_name": "why a value is missing"}),
    }
    attrs = {**_field_attrs("a_", d["a"]), **_field_attrs("b_", d["b"]), "lmax": -1 if lmax is None else int(lmax),
             "b_resampled_onto_a_grid": int(d["regridded"]), "Conventions": "CF-1.8",
             "source": "raypc correlate (docs/compare.md)"}
    return xr.Dataset(data, coords=_depth_coord(d["depth_km"], d["radius_km"]), attrs=attrs)


def spectrum(ds: FieldInput, var: Optional[str] = None, lmax: Optional[int] = None, step=0) -> "xr.DataArray":
    """The spherical-harmonic power per degree of a field at every depth (4π-normalised real harmonics:
    the sum over degrees is the mean square over the sphere), ``raypc spectrum DS[:VAR] [--lmax L]``'s
    table as an xarray.DataArray (depth, degree), depth a CF coordinate (km, positive down). ``lmax``:
    None for the grid's largest degree, at most 60. Refused (raypc.Error, naming the reason) for a
    regional grid, longitudes that are not evenly spaced, or missing values."""
    import xarray as xr

    d = _raypc.spectrum(_input(ds), var or "", _step(step), _lmax(lmax))
    f = d["field"]
    units = f["units"] or "1"
    coords = _depth_coord(d["depth_km"], d["radius_km"])
    coords["degree"] = ("degree", np.arange(d["lmax"] + 1), {"long_name": "spherical-harmonic degree l", "units": "1"})
    return xr.DataArray(d["power"], dims=("depth", "degree"), coords=coords, name="power",
                        attrs={"units": f"({units})^2" if "/" in units or " " in units else f"{units}^2",
                               "long_name": f"power per degree of {f['variable']}",
                               "normalisation": "4pi-normalised real harmonics; sum over degrees = mean square",
                               "quadrature": d["quadrature"], **_field_attrs("", f),
                               "source": "raypc spectrum (docs/compare.md)"})


def degree_correlation(a: FieldInput, b: FieldInput, depth: float, var_a: Optional[str] = None,
                       var_b: Optional[str] = None, lmax: Optional[int] = None, step=0, step_b=None) -> "xr.Dataset":
    """The per-degree correlation of two fields on ``a``'s shell nearest ``depth`` (km) and each one's
    power per degree: ``raypc spectrum A[:VAR] --with B[:VAR] --depth D``'s table as an xarray.Dataset on
    ``degree``; the shell's depth is the scalar coordinate ``depth``."""
    import xarray as xr

    d = _raypc.degree_correlation(_input(a), var_a or "", _step(step), _input(b), var_b or "",
                                  _step(step if step_b is None else step_b), float(depth), _lmax(lmax))
    ua, ub = d["a"]["units"] or "1", d["b"]["units"] or "1"
    coords = {"degree": ("degree", np.arange(d["lmax"] + 1), {"long_name": "spherical-harmonic degree l", "units": "1"}),
              "depth": ((), d["depth_km"], {"units": "km", "positive": "down", "standard_name": "depth"}),
              "radius": ((), d["radius_km"], {"units": "km"})}
    data = {"correlation": ("degree", d["correlation"], {"units": "1", "long_name": "per-degree correlation r_l"}),
            "power_a": ("degree", d["power_a"], {"units": f"{ua}^2", "long_name": f"power per degree of {d['a']['variable']}"}),
            "power_b": ("degree", d["power_b"], {"units": f"{ub}^2", "long_name": f"power per degree of {d['b']['variable']}"})}
    return xr.Dataset(data, coords=coords, attrs={**_field_attrs("a_", d["a"]), **_field_attrs("b_", d["b"]),
                                                 "source": "raypc spectrum --with (docs/compare.md)"})
