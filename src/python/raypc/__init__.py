"""RayPC from Python: mantle convection datasets as NumPy arrays, xarray Datasets and pandas
DataFrames; render states, pictures and exact statistics; the browser UI in a notebook, linked both
ways (docs/python.md).

Everything here calls the compiled module ``raypc._raypc``, which is linked to the same libraries as
the ``raypc`` executable: a picture equals ``raypc render``'s, a table ``raypc stats``', a probe
``raypc probe``'s. Errors are :class:`raypc.Error` (a ValueError) with the command line's one-line
messages, naming Python's arguments; a missing file is also a FileNotFoundError, an unknown variable
a KeyError, a step or level out of range an IndexError (docs/python.md, "Errors").

>>> import raypc
>>> ds = raypc.open("demo-data/dataset")                     # a dataset, netCDF files or ASPECT's solution.pvd
>>> ds.to_xarray(6).temperature.sel(depth=660, method="nearest").plot()   # lazy, CF names
>>> xr.open_dataset("demo-data/dataset", engine="raypc")          # the whole series, lazy
>>> state = raypc.State("examples/task1-slabs-660km.json")
>>> ds.stats(state).plot(x="time_myr", y="selected_percent_of_mantle")
>>> raypc.correlate(ds, "other.raypc", lmax=20).correlation.plot(y="depth", yincrease=False)  # docs/compare.md
"""
from __future__ import annotations

import os as _os

# An installed package carries the UI's coastlines (web/coastlines.json): pictures with
# reference.coastlines find them there unless $RAYPC_COASTLINES says otherwise (in the build tree the
# source tree's web/dist is found as before).
_COASTLINES = _os.path.join(_os.path.dirname(_os.path.abspath(__file__)), "web", "coastlines.json")
if _os.path.isfile(_COASTLINES):
    _os.environ.setdefault("RAYPC_COASTLINES", _COASTLINES)

from . import _raypc  # noqa: E402 (after the coastlines' default, which the compiled module reads)
from ._raypc import Error, NotFoundError, OutOfRangeError, UnknownNameError
from ._raypc import __version__  # project(VERSION) in CMakeLists.txt, as the wheel's metadata
from .compare import correlate, degree_correlation, spectrum
from .dataset import Dataset, StepLike
from .difference import diff
from .grid import SURFACE_RADIUS_KM, Field, Grid, Variable
from .names import NAMES
from .picture import Picture
from .preprocess import open
from .state import STATE_VERSION, State
from .view import View, show

__all__ = ["Error", "NotFoundError", "UnknownNameError", "OutOfRangeError", "open", "diff", "Dataset", "State", "Field",
           "Grid", "Variable", "Picture", "View", "show", "NAMES", "correlate", "spectrum", "degree_correlation"]
