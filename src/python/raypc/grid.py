"""The spherical grid of a dataset and what it holds: a level's coordinates (:class:`Grid`), one
variable of one step on them (:class:`Field`), and what a variable is (:class:`Variable`)."""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from . import _raypc

SURFACE_RADIUS_KM: float = _raypc.surface_radius_km()


class Variable(NamedTuple):
    """A variable of a dataset: its global range over all steps, in its units."""

    name: str
    units: str
    min: float
    max: float
    derived: bool


class Grid(NamedTuple):
    """The spherical grid of one level of detail: latitude (degrees north), radius (km) and
    longitude (degrees east, [0, 360)), each ascending; values are stored (lat, r, lon)."""

    lat: np.ndarray
    r: np.ndarray
    lon: np.ndarray

    @property
    def depth(self) -> np.ndarray:
        """Depth below the surface (km) of every radius."""
        return SURFACE_RADIUS_KM - self.r

    @property
    def shape(self) -> tuple:
        return (len(self.lat), len(self.r), len(self.lon))

    def __repr__(self) -> str:
        return (f"<raypc.Grid {len(self.lat)} lat ({self.lat[0]:g}..{self.lat[-1]:g} °N) x {len(self.r)} r "
                f"({self.r[0]:g}..{self.r[-1]:g} km) x {len(self.lon)} lon ({self.lon[0]:g}..{self.lon[-1]:g} °E)>")


class Field(NamedTuple):
    """One variable of one step: ``values`` (lat, r, lon) float32 in ``units``, NaN where the data
    have none, with the grid's coordinates (degrees north, km radius, degrees east)."""

    values: np.ndarray
    lat: np.ndarray
    r: np.ndarray
    lon: np.ndarray
    name: str
    units: str
    step: int
    time_myr: float
    level: int

    def __repr__(self) -> str:
        # Short: what it is and its range, not the arrays (a notebook prints this for every Field).
        v = self.values
        finite = v[np.isfinite(v)]
        span = f"{finite.min():.6g}..{finite.max():.6g} {self.units}".rstrip() if finite.size else "no data"
        missing = v.size - finite.size
        return (f"<raypc.Field {self.name!r} step {self.step} ({self.time_myr:g} Myr), level {self.level}: "
                f"{v.shape[0]} lat x {v.shape[1]} r x {v.shape[2]} lon, {span}"
                + (f", {missing} missing" if missing else "") + ">")
