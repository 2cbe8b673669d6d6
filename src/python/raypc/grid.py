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


class Field(NamedTuple):
    """One variable of one step: ``values`` (lat, r, lon) float32 with the grid's coordinates."""

    values: np.ndarray
    lat: np.ndarray
    r: np.ndarray
    lon: np.ndarray
    name: str
    units: str
    step: int
    time_myr: float
    level: int
