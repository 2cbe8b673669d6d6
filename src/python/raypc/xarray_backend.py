"""RayPC datasets as lazy xarray Datasets: ``xr.open_dataset("demo-data/dataset", engine="raypc")``
(the ``xarray.backends`` entry point ``raypc``), and :meth:`raypc.Dataset.to_xarray`.

The whole series is one Dataset on (time, lat, radius, lon) with a ``depth`` coordinate on radius
that is indexed as well, so that ``sel(depth=660, method="nearest")`` and ``sel(radius=5711,
method="nearest")`` both work. Opening reads the manifest only; a variable's values are read when
asked for, one step at a time and only the grid-index box asked for (``_raypc.Dataset.read_box``:
a stored variable's values at those points, a shell anomaly from its base's values on the box's
shells). With dask, ``chunks={}`` gives a chunk per step and variable (``preferred_chunks``).

Names are CF-safe (``raypc.names.cf_name``: ``temperature anomaly %`` is
``temperature_anomaly_percent``); the display name is the variable's ``long_name``.

Time is a dimension in Myr of model time: units ``Myr`` (udunits: mega-years, convertible to the
``s`` of standard_name ``time``). Not ``Myr since …``: a model's time has no calendar date, and
xarray (and CF readers) would decode a ``since`` unit as dates; and not a unit xarray decodes as a
time delta (``days``, ``seconds``), so that a netCDF round trip keeps the float Myr values."""
from __future__ import annotations

import datetime
import os
from pathlib import Path
from typing import TYPE_CHECKING, Iterable, Optional, Union

import numpy as np
import xarray as xr
from xarray.backends import BackendArray, BackendEntrypoint
from xarray.core import indexing

from ._raypc import Error, OutOfRangeError

if TYPE_CHECKING:
    from .dataset import Dataset

_MANIFEST = "dataset.json"  # dataset/dataset_format.h kManifest
_FORMAT_NAME = "raypc-dataset"  # its kFormatName


def _is_raypc_dataset(path) -> bool:
    try:
        manifest = Path(os.fspath(path)) / _MANIFEST
        if not manifest.is_file():
            return False
        # The manifest's keys are sorted: "format" comes within its first lines (the whole file holds
        # every step's statistics and may be large).
        with open(manifest, "rb") as f:
            return f'"{_FORMAT_NAME}"'.encode() in f.read(65536)
    except (TypeError, OSError):
        return False


class RaypcBackendArray(BackendArray):
    """One variable of every step at one level, (time, lat, radius, lon) float32, read lazily."""

    def __init__(self, core, variable: str, level: int, shape: tuple):
        self._core = core  # raypc._raypc.Dataset: immutable, its reads are thread-safe without the GIL
        self._variable = variable  # the display name, as the compiled module takes it
        self._level = level
        self.shape = shape
        self.dtype = np.dtype("float32")

    def __getitem__(self, key: indexing.ExplicitIndexer) -> np.ndarray:
        # BASIC: xarray turns every other indexing (outer, vectorized) into slices and ints here and
        # applies the rest to what this returns.
        return indexing.explicit_indexing_adapter(key, self.shape, indexing.IndexingSupport.BASIC, self._read)

    def _read(self, key: tuple) -> np.ndarray:
        picks = []  # per axis: the indices, and whether an int dropped the axis
        for k, n in zip(key, self.shape):
            if isinstance(k, slice):
                picks.append((np.arange(n)[k], False))
            else:
                picks.append((np.array([int(k) % n if -n <= int(k) < n else int(k)]), True))
        shape = tuple(len(p) for p, _ in picks)
        out = np.empty(shape, dtype=self.dtype)
        if out.size:
            (steps, _), *space = picks
            # The box that holds the picked indices of each spatial axis, then the picks within it
            # (a strided slice reads its span: the points between are in the same bricks anyway).
            begin = [int(p.min()) for p, _ in space]
            end = [int(p.max()) + 1 for p, _ in space]
            within = np.ix_(*[p - b for (p, _), b in zip(space, begin)])
            for i, step in enumerate(steps):
                box = self._core.read_box(self._variable, int(step), self._level, begin, end)
                out[i] = box[within]
        return out[tuple(0 if dropped else slice(None) for _, dropped in picks)]


def open_raypc_dataset(dataset: "Dataset", variables: Optional[Iterable[str]] = None, level: int = 0,
                       drop_variables: Optional[Iterable[str]] = None) -> xr.Dataset:
    """The lazy whole-series Dataset of a :class:`raypc.Dataset` (see the module's text).
    ``variables``/``drop_variables``: names, display or CF, to keep or to leave out."""
    if isinstance(level, bool) or not isinstance(level, (int, np.integer)):
        raise TypeError(f"level: expected an integer level of detail, not {level!r}")
    if not 0 <= level < len(dataset.levels):
        raise OutOfRangeError(f"level: {level} out of range 0..{len(dataset.levels) - 1}")
    level = int(level)
    display = [v.name for v in dataset.variables]
    cf = dataset._cf_names
    if isinstance(variables, str):
        variables = [variables]
    if isinstance(drop_variables, str):
        drop_variables = [drop_variables]
    keep = display if variables is None else [dataset._variable_name(v) for v in variables]
    if not keep:
        raise Error("variables: none given")
    # As xarray's other engines do, a name to drop that the dataset does not have is no error.
    known = set(display) | set(cf.values())
    drop = {dataset._variable_name(v) for v in drop_variables or () if v in known}
    keep = [v for v in keep if v not in drop]

    g = dataset.levels[level]
    times = np.asarray(dataset.times, dtype=np.float64)
    shape = (len(times), len(g.lat), len(g.r), len(g.lon))
    dims = ("time", "lat", "radius", "lon")
    units = {v.name: v.units for v in dataset.variables}
    data_vars = {}
    for name in keep:
        array = indexing.LazilyIndexedArray(RaypcBackendArray(dataset._core, name, level, shape))
        attrs = {"long_name": name}
        if units[name]:
            attrs["units"] = units[name]
        var = xr.Variable(dims, array, attrs)
        # A dask chunk per step and variable (xarray's open_dataset(chunks={}) takes these).
        var.encoding["preferred_chunks"] = dict(zip(dims, (1,) + shape[1:]))
        data_vars[cf[name]] = var
    coords = {
        "time": ("time", times, {"standard_name": "time", "long_name": "model time", "units": "Myr", "axis": "T"}),
        "lat": ("lat", np.asarray(g.lat), {"standard_name": "latitude", "long_name": "latitude",
                                           "units": "degrees_north", "axis": "Y"}),
        "radius": ("radius", np.asarray(g.r), {"long_name": "distance from the Earth's centre", "units": "km",
                                               "axis": "Z", "positive": "up"}),
        "lon": ("lon", np.asarray(g.lon), {"standard_name": "longitude", "long_name": "longitude",
                                           "units": "degrees_east", "axis": "X"}),
        "depth": ("radius", np.asarray(g.depth), {"standard_name": "depth", "long_name": "depth below the surface",
                                                  "units": "km", "positive": "down"}),
    }
    now = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    attrs = {"Conventions": "CF-1.8", "title": f"RayPC dataset {dataset.path.name}",
             "source": f"RayPC dataset {dataset.path}", "history": f"{now}: opened by raypc's xarray backend",
             "level": level, "raypc_encoding": dataset._core.encoding}
    x = xr.Dataset(data_vars, coords=coords, attrs=attrs)
    # depth is radius' second index: sel(depth=…) as sel(radius=…).
    return x.set_xindex("depth")


class RaypcBackendEntrypoint(BackendEntrypoint):
    """xarray's backend for RayPC dataset directories (docs/python.md, "xarray"):
    ``xr.open_dataset(path, engine="raypc", level=0)``."""

    description = "Open RayPC preprocessed mantle convection datasets (a directory with dataset.json), lazily"
    url = "docs/python.md#xarray"  # the repository has no public address to name yet
    open_dataset_parameters = ("filename_or_obj", "drop_variables", "level")

    def open_dataset(self, filename_or_obj: Union[str, os.PathLike], *, drop_variables=None, level: int = 0):
        from .dataset import Dataset  # here: the dataset module imports this one

        if not isinstance(filename_or_obj, (str, os.PathLike)):
            raise TypeError(f"raypc engine: expected the path of a RayPC dataset directory, not {type(filename_or_obj).__name__}")
        dataset = Dataset(filename_or_obj)
        return open_raypc_dataset(dataset, level=level, drop_variables=drop_variables)

    def guess_can_open(self, filename_or_obj) -> bool:
        return _is_raypc_dataset(filename_or_obj)
