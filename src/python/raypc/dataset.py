"""A preprocessed dataset (docs/format.md) and what Python asks of it: its variables, steps and
grids; fields as NumPy arrays and xarray Datasets; probes, samples, pathlines and critical points;
states rendered to pictures, exact statistics and features. Each answer is computed by the code of
the matching ``raypc`` command (render, stats, features, probe), so that the two agree."""
from __future__ import annotations

import json
import numbers
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any, Optional, Sequence, Union

import numpy as np

from . import _raypc
from ._progress import _Progress
from ._raypc import Error
from .grid import SURFACE_RADIUS_KM, Field, Grid, Variable
from .names import _COLUMNS, _PATHLINE_ATTRIBUTE
from .picture import Picture
from .state import State

if TYPE_CHECKING:
    from .view import View

StepLike = Union[int, str]  # 12, or a time such as "24Myr"


def _state_of(state: Union[None, State, dict, str, os.PathLike], dataset: "Dataset") -> State:
    if state is None:
        return dataset.default_state()
    return state if isinstance(state, State) else State(state)


class Dataset:
    """A preprocessed RayPC dataset (docs/format.md); see :func:`raypc.open`."""

    def __init__(self, directory: Union[str, os.PathLike]):
        self._core = _raypc.Dataset(os.fspath(directory))
        # What the dataset is, read once (it does not change while open); arrays read-only, shared.
        self._variables = [Variable(v["name"], v["units"], v["min"], v["max"], v["derived"])
                           for v in self._core.variables]
        self._units = {v.name: v.units for v in self._variables}
        self._levels = [Grid(g["lat"], g["r"], g["lon"]) for g in self._core.levels]
        self._times = self._core.times_myr
        for a in [self._times] + [a for g in self._levels for a in g]:
            a.flags.writeable = False

    # ---- what it is -------------------------------------------------------------------------

    @property
    def path(self) -> Path:
        return Path(self._core.dir)

    @property
    def variables(self) -> list:
        """The variables (stored and derived) with units and global ranges, in dataset order."""
        return list(self._variables)

    @property
    def steps(self) -> range:
        return range(len(self._times))

    @property
    def times(self) -> np.ndarray:
        """The time of every step, Myr."""
        return self._times

    @property
    def levels(self) -> list:
        """The grid of every level of detail (0 = full resolution)."""
        return list(self._levels)

    @property
    def grid(self) -> Grid:
        """The full-resolution grid (level 0)."""
        return self._levels[0]

    def __repr__(self) -> str:
        g = self.grid
        t = self.times
        variables = ", ".join(f"{v.name} [{v.units}]" if v.units else v.name for v in self.variables)
        return (f"<raypc.Dataset {str(self.path)!r}: {len(t)} steps, {t[0]:g}..{t[-1]:g} Myr; grid "
                f"{len(g.lat)} lat x {len(g.r)} r x {len(g.lon)} lon ({g.r[0]:.0f}..{g.r[-1]:.0f} km), "
                f"{len(self.levels)} levels, {self._core.encoding}; variables: {variables}>")

    def _step(self, step: StepLike, what: str = "step") -> int:
        # str() would accept anything (a float, a list) and the message would blame its text; the
        # wrong type is a TypeError. bool is an int to Python but never meant as a step.
        if isinstance(step, numbers.Integral) and not isinstance(step, bool):
            return self._core.step(str(int(step)), what)
        if isinstance(step, str):
            return self._core.step(step, what)
        raise TypeError(f"{what}: expected a step index (int) or a time such as '24Myr' (str), "
                        f"not {type(step).__name__}")

    # ---- values -----------------------------------------------------------------------------

    def field(self, variable: str, step: StepLike = 0, level: int = 0) -> Field:
        """One variable of one step on the native grid, (lat, r, lon) float32 (a copy)."""
        s = self._step(step)
        values = self._core.field(variable, s, level)  # checks the variable and the level
        g = self._levels[level]
        return Field(values, g.lat, g.r, g.lon, variable, self._units[variable], s, float(self._times[s]), level)

    def to_xarray(self, step: StepLike = 0, variables: Optional[Sequence[str]] = None, level: int = 0):
        """The step as an ``xarray.Dataset`` on (lat, r, lon) with CF attributes and units, a depth
        coordinate on r and the time (Myr): ``ds.to_xarray(6)["temperature"].sel(r=5711,
        method="nearest").plot()``."""
        import xarray as xr

        s = self._step(step)
        if isinstance(variables, str):
            variables = [variables]
        names = [v.name for v in self._variables] if variables is None else list(variables)
        if not names:
            raise Error("variables: none given")
        data_vars = {}
        for name in names:
            f = self.field(name, s, level)
            data_vars[name] = (("lat", "r", "lon"), f.values, {"long_name": name, "units": f.units})
        g = self._levels[level]
        coords = {
            "lat": ("lat", g.lat, {"standard_name": "latitude", "units": "degrees_north", "axis": "Y"}),
            "r": ("r", g.r, {"long_name": "radius", "units": "km", "axis": "Z", "positive": "up"}),
            "lon": ("lon", g.lon, {"standard_name": "longitude", "units": "degrees_east", "axis": "X"}),
            "depth": ("r", g.depth, {"standard_name": "depth", "long_name": "depth below the surface", "units": "km",
                                     "positive": "down"}),
            "time": ((), float(self._times[s]), {"standard_name": "time", "long_name": "model time", "units": "Myr"}),
        }
        return xr.Dataset(data_vars, coords=coords,
                          attrs={"Conventions": "CF-1.8", "source": f"RayPC dataset {self.path}", "step": s,
                                 "level_of_detail": level})

    def probe(self, lat: float, lon: float, r_km: float, step: StepLike = 0, level: int = 0,
              variable: Optional[str] = None) -> dict:
        """The values at one point, interpolated as ``raypc probe`` does, in its JSON's shape:
        ``{"step", "time_myr", "level", "point": {...}, "values": {NAME: {"value", "units",
        "quantisation_error_max"}}}``."""
        return json.loads(self._core.probe(float(lat), float(lon), float(r_km), self._step(step), level,
                                           variable or ""))

    def sample(self, step: StepLike = 0):
        """The parallel-coordinates sample of a step (the same cells in every step) as a
        ``pandas.DataFrame``: coordinate columns then variables; units in ``df.attrs["units"]``."""
        import pandas as pd

        columns, units, values = self._core.sample(self._step(step))
        df = pd.DataFrame(values, columns=columns)
        df.attrs["units"] = dict(zip(columns, units))
        return df

    def pathlines(self, step: StepLike = 0, window: int = 10) -> list:
        """The pathline sets injected in the ``window`` steps up to ``step`` (as the UI shows them),
        each a dict: ``injection_step``, ``injection_time_myr``, ``seed_field``, ``lines`` (a
        DataFrame of per-line attributes, units in ``.attrs``) and ``points`` (a DataFrame of x, y, z
        km, time Myr and the line index)."""
        import pandas as pd

        out = []
        if isinstance(window, bool) or not isinstance(window, numbers.Integral):
            raise TypeError(f"window: expected a number of steps (int), not {type(window).__name__}")
        for s in self._core.pathlines(self._step(step), int(window)):
            lines = pd.DataFrame(s["attributes"], columns=s["columns"])
            lines.attrs["units"] = dict(zip(s["columns"], s["units"]))
            offsets = s["offsets"]
            line_of_point = np.repeat(np.arange(len(offsets) - 1), np.diff(offsets))
            points = pd.DataFrame(s["points"], columns=[c["column"] for c in _COLUMNS["pathlinePoints"]])
            points["line"] = line_of_point
            out.append({"injection_step": s["injection_step"], "injection_time_myr": s["injection_time_myr"],
                        "end_step": s["end_step"], "seed_field": s["seed_field"], "threshold": s["threshold"],
                        "lines": lines, "points": points})
        return out

    def critical_points(self, step: StepLike = 0):
        """The significant critical points of the seed field that seeded the pathlines of ``step``
        (docs/persistence.md) as a DataFrame: kind, lat, lon, radius_km, depth_km, value,
        persistence."""
        import pandas as pd

        (stored,) = self._core.pathlines(self._step(step), 1)  # the set injected at the step
        lines = pd.DataFrame(stored["attributes"], columns=stored["columns"])
        a = _PATHLINE_ATTRIBUTE
        kinds = lines[a["seedKind"]].astype(int)
        df = pd.DataFrame({
            "kind": [_raypc.critical_kind_name(k) for k in kinds],
            "lat": lines[a["startLat"]], "lon": lines[a["startLon"]], "radius_km": lines[a["startRadius"]],
            "depth_km": SURFACE_RADIUS_KM - lines[a["startRadius"]], "value": lines[a["seedValue"]],
            "persistence": lines[a["seedPersistence"]] if a["seedPersistence"] in lines else np.nan})
        df.attrs["seed_field"] = stored["seed_field"]
        return df

    # ---- states, pictures, statistics ---------------------------------------------------------

    def default_state(self) -> State:
        """The UI's first view of this dataset (what ``raypc render`` draws without --state)."""
        return State(self._core.default_state())

    def check_state(self, state: Union[State, dict, str, os.PathLike]) -> State:
        """The state checked against this dataset (variables, step, level), normalised."""
        return State(self._core.check_state(_state_of(state, self).to_json(None)))

    def render(self, state: Union[None, State, dict, str, os.PathLike] = None, size: Optional[tuple] = None,
               passes: Optional[int] = None, step: Optional[StepLike] = None, progress: bool = True,
               view: str = "3d") -> Picture:
        """The picture of a state (default: the UI's first view), as ``raypc render --state`` writes
        it: (height, width, 4) uint8 RGBA. ``size`` (width, height) and ``step`` override the
        state's; ``passes`` the state's number of progressive passes. Runs on all cores without the
        GIL, with a progress bar per pass (``progress=False`` silences it); Ctrl-C stops it.
        ``view="map"`` or ``"section"`` draws the state's map or section instead (its ``map`` and
        ``section`` keys, docs/maps.md), as ``raypc map`` and ``raypc section`` do."""
        s = _state_of(state, self).to_dict()
        if size is not None:
            w, h = size
            s["image"] = {"width": int(w), "height": int(h)}
        if step is not None:
            s["step"] = self._step(step)
        bar = _Progress("render", progress, delay=0.5)
        try:
            pixels = self._core.render(json.dumps(s), 0 if passes is None else int(passes), view, bar)
        finally:
            bar.close()
        return pixels.view(Picture)

    def stats(self, state: Union[None, State, dict, str, os.PathLike] = None, steps: Optional[Any] = None,
              level: int = 0, by: str = "step", mean_of: Optional[str] = None, progress: bool = True):
        """The exact selected volume of the state's brushes (``raypc stats``) as a DataFrame.
        ``by="step"``: step, time_myr, selected_volume_km3, selected_percent_of_mantle;
        ``by="depth"``: per step and radius, the depth profile (``raypc stats --profile``), and with
        ``mean_of=NAME`` that variable's volume-weighted mean per radius over the selection (NaN
        where nothing is selected) and over the whole shell (``--profile-var``), columns named as
        the CLI's (``NAME selected mean [units]``, ``NAME shell mean [units]``): a time-depth table
        (``df.pivot(index="depth_km", columns="time_myr", values=...)``).
        ``steps``: None (all), a step, a (first, last) pair or a range."""
        import pandas as pd

        if by not in ("step", "depth"):
            raise Error(f"by: expected 'step' or 'depth', not {by!r}")
        if mean_of is not None and by != "depth":
            raise Error("mean_of: the means are per depth; ask for by='depth'")
        first, last = self._step_range(steps)
        bar = _Progress("stats", progress, delay=0.5)
        try:
            rows = self._core.stats(_state_of(state, self).to_json(None), first, last, level, mean_of or "", bar)
        finally:
            bar.close()
        # The columns as NAMES names them, the values in its order (the CLI's CSV files).
        if by == "step":
            names = [c["name"] for c in _COLUMNS["selectionOverTime"]]
            values = ([r[0] for r in rows], [r[1] for r in rows], [r[2] for r in rows], [100.0 * r[3] for r in rows])
            return pd.DataFrame(dict(zip(names, values, strict=True)))
        r_km = self._levels[level].r
        units = {v.name: v.units for v in self.variables}.get(mean_of, "")
        names = [c["name"] for c in _COLUMNS["profile"]]
        means = [p.format(name=mean_of, units=units) for p in _COLUMNS["profileMeans"]] if mean_of is not None else []
        parts = []
        for step, t, _, _, by_radius, shell, selected_mean, shell_mean in rows:
            columns = dict(zip(names, (step, t, r_km, SURFACE_RADIUS_KM - r_km, by_radius, shell,
                                       100.0 * by_radius / shell), strict=True))
            if means:
                columns.update(zip(means, (selected_mean, shell_mean), strict=True))
            parts.append(pd.DataFrame(columns))
        return pd.concat(parts, ignore_index=True)

    def features(self, state: Union[None, State, dict, str, os.PathLike] = None, steps: Optional[Any] = None,
                 level: Optional[int] = None, min_volume_km3: Optional[float] = None,
                 depths_km: Optional[Sequence[float]] = None, band_half_width_km: Optional[float] = None,
                 progress: bool = True):
        """The features of the state's brushes in each step (``raypc features``, docs/features.md) as a
        DataFrame: a row per feature and step with its volume, depths, centroid, every variable's
        mean/min/max (units in the column names) and the percent of its volume near each depth.
        ``steps`` as for :meth:`stats`. The settings left at None come from the state's ``features``
        (level, minVolumeKm3, depthsKm, bandHalfWidthKm; state version 10), as ``raypc features
        --state`` takes them."""
        import io

        import pandas as pd

        state = _state_of(state, self)
        settings = state.to_dict()["features"]
        level = settings["level"] if level is None else level
        min_volume_km3 = settings["minVolumeKm3"] if min_volume_km3 is None else min_volume_km3
        depths_km = settings["depthsKm"] if depths_km is None else depths_km
        band_half_width_km = settings["bandHalfWidthKm"] if band_half_width_km is None else band_half_width_km
        first, last = self._step_range(steps)
        bar = _Progress("features", progress, delay=0.5)
        try:
            text = self._core.features(state.to_json(None), first, last, level, float(min_volume_km3),
                                       [float(d) for d in depths_km], float(band_half_width_km), bar)
        finally:
            bar.close()
        return pd.read_csv(io.StringIO(text))

    def _step_range(self, steps: Any) -> tuple:
        if steps is None:
            return 0, len(self._times) - 1
        if isinstance(steps, range):
            if len(steps) == 0 or steps.step != 1:
                raise Error(f"steps: {steps} is not a non-empty range of consecutive steps")
            return self._step(steps[0], "steps"), self._step(steps[-1], "steps")
        if isinstance(steps, (tuple, list)) and len(steps) == 2:
            return self._step(steps[0], "steps"), self._step(steps[1], "steps")
        if isinstance(steps, (tuple, list)):
            raise TypeError(f"steps: expected None, a step, a (first, last) pair or a range, not a "
                            f"{type(steps).__name__} of {len(steps)}")
        s = self._step(steps, "steps")
        return s, s

    def show(self, **kwargs: Any) -> "View":
        """The browser UI of this dataset, in a notebook: see :func:`raypc.show`."""
        from .view import show  # here, not above: the view module imports this one

        return show(self, **kwargs)
