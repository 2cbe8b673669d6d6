"""A preprocessed dataset (docs/format.md) and what Python asks of it: its variables, steps and
grids; fields as NumPy arrays and xarray Datasets; probes, samples, pathlines and critical points;
states rendered to pictures, exact statistics and features. Each answer is computed by the code of
the matching ``raypc`` command (render, stats, features, probe), so that the two agree."""
from __future__ import annotations

import json
import numbers
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any, NamedTuple, Optional, Sequence, Union

import numpy as np

from . import _raypc
from ._progress import _Progress
from ._raypc import Error, UnknownNameError
from .grid import SURFACE_RADIUS_KM, Field, Grid, Variable
from .names import _COLUMNS, _PATHLINE_ATTRIBUTE, cf_names
from .picture import Picture
from .state import State

if TYPE_CHECKING:  # for the annotations only: pandas, xarray and VTK are imported where used
    import pandas as pd
    import xarray as xr
    from vtkmodules.vtkCommonDataModel import vtkStructuredGrid

    from .view import View

StepLike = Union[int, str]  # 12, or a time such as "24Myr"


def _state_of(state: Union[None, State, dict, str, os.PathLike], dataset: "Dataset") -> State:
    if state is None:
        return dataset.default_state()
    return state if isinstance(state, State) else State(state)


class FeatureTracks(NamedTuple):
    """Features followed through a series (:meth:`Dataset.tracks`), the tables of ``raypc features
    --tracks/--events/--stalls`` and ``raypc flux`` (columns in docs/features.md)."""

    tracks: "pd.DataFrame"   # DataFrame: a row per track and step (volume km³, mean depth km, centroid)
    events: "pd.DataFrame"   # DataFrame: births, deaths, merges and splits
    stalls: "pd.DataFrame"   # DataFrame: how long each track stays near each depth (Myr) and how it left
    flux: "Optional[pd.DataFrame]"  # DataFrame: the flux across the shells per step (km³/yr), None without shells in the grid
    settings: dict   # the settings used (level, minVolumeKm3, depthsKm, bandHalfWidthKm, minOverlapShare, stallBy)

    def __repr__(self) -> str:
        flux = "none" if self.flux is None else f"{len(self.flux)} rows"
        return (f"<raypc.FeatureTracks: {self.tracks['track'].nunique()} tracks, {len(self.events)} events, "
                f"{len(self.stalls)} stalls, flux {flux}; stall by {self.settings['stallBy']}>")


def _grid_array(d: dict) -> "xr.DataArray":
    """A slice grid of the compiled module (app/slice_grid.h's CF grid) as an xarray.DataArray."""
    import xarray as xr

    def attrs(v: dict) -> dict:
        keys = ("units", "standard_name", "long_name", "axis", "positive")
        return {k: v[k] for k in keys if v[k]}

    rows, columns = d["rows"], d["columns"]
    coords = {rows["name"]: (rows["name"], rows["values"], attrs(rows)),
              columns["name"]: (columns["name"], columns["values"], attrs(columns))}
    for v in d["auxiliary"]:
        coords[v["name"]] = (v["dimension"], v["values"], attrs(v))
    for v in d["scalars"]:
        coords[v["name"]] = ((), float(v["values"][0]), attrs(v))
    out_attrs = {"long_name": d["long_name"], "units": d["units"], **dict(d["attributes"])}
    return xr.DataArray(d["values"], dims=(rows["name"], columns["name"]), coords=coords, name=d["name"],
                        attrs=out_attrs)


class Dataset:
    """A preprocessed RayPC dataset (docs/format.md); see :func:`raypc.open`."""

    def __init__(self, directory: Union[str, os.PathLike]) -> None:
        self._core = _raypc.Dataset(os.fspath(directory))
        # What the dataset is, read once (it does not change while open); arrays read-only, shared.
        self._variables = [Variable(v["name"], v["units"], v["min"], v["max"], v["derived"])
                           for v in self._core.variables]
        self._units = {v.name: v.units for v in self._variables}
        self._cf_names = cf_names(self._units)  # display name -> CF name, unique (to_xarray's names)
        self._display_names = {cf: display for display, cf in self._cf_names.items()}
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

    def _repr_html_(self) -> str:
        """The dataset in a notebook: its grid, steps and variables with units and global ranges."""
        from html import escape

        g, t = self.grid, self.times
        rows = "".join(
            f"<tr><td style='text-align:left'>{escape(v.name)}</td><td style='text-align:left'>{escape(v.units)}</td>"
            f"<td>{v.min:.6g}</td><td>{v.max:.6g}</td>"
            f"<td style='text-align:left'>{'derived' if v.derived else 'stored'}</td></tr>" for v in self.variables)
        levels = ", ".join(f"{len(l.lat)}×{len(l.r)}×{len(l.lon)}" for l in self.levels)
        return (f"<div><b>raypc.Dataset</b> <code>{escape(str(self.path))}</code><br>"
                f"{len(t)} steps, {t[0]:g}–{t[-1]:g} Myr; grid {len(g.lat)} lat × {len(g.r)} r × {len(g.lon)} lon, "
                f"lat {g.lat[0]:g}..{g.lat[-1]:g} °N, lon {g.lon[0]:g}..{g.lon[-1]:g} °E, "
                f"radius {g.r[0]:.0f}..{g.r[-1]:.0f} km (depth {SURFACE_RADIUS_KM - g.r[-1]:.0f}..{SURFACE_RADIUS_KM - g.r[0]:.0f} km); "
                f"levels {levels}; values {escape(self._core.encoding)}"
                f"<table><thead><tr><th style='text-align:left'>variable</th><th style='text-align:left'>units</th>"
                f"<th>min</th><th>max</th><th style='text-align:left'></th></tr></thead><tbody>{rows}</tbody></table></div>")

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
        variable = self._variable_name(variable)
        values = self._core.field(variable, s, level)  # checks the variable and the level
        g = self._levels[level]
        return Field(values, g.lat, g.r, g.lon, variable, self._units[variable], s, float(self._times[s]), level)

    def _variable_name(self, name: str, what: str = "variable") -> str:
        """The display name of a variable named by its display name or its CF name (to_xarray's)."""
        if not isinstance(name, str):
            raise TypeError(f"{what}: expected a name, not {type(name).__name__}")
        if name in self._units:
            return name
        if name in self._display_names:
            return self._display_names[name]
        raise UnknownNameError(f"{what}: unknown variable '{name}'; the dataset has: {', '.join(self._units)}")

    def to_xarray(self, step: Optional[StepLike] = None, variables: Optional[Sequence[str]] = None, level: int = 0) -> "xr.Dataset":
        """The dataset as a lazy ``xarray.Dataset`` on (time, lat, radius, lon), as
        ``xr.open_dataset(path, engine="raypc")`` opens it (raypc.xarray_backend): CF names
        (``temperature_anomaly``), attributes and units, ``depth`` indexed too; values read when
        used, only those used. ``step``: that step alone (``.isel(time=step)``, a scalar time, and
        the attribute ``step``): ``ds.to_xarray(6).temperature.sel(depth=660, method="nearest").plot()``.
        ``variables``: names, display or CF, to keep (default all)."""
        from .xarray_backend import open_raypc_dataset

        x = open_raypc_dataset(self, variables, level)
        if step is None:
            return x
        s = self._step(step)
        x = x.isel(time=s)
        x.attrs["step"] = s
        return x

    def probe(self, lat: float, lon: float, r_km: float, step: StepLike = 0, level: int = 0,
              variable: Optional[str] = None) -> dict:
        """The values at one point, interpolated as ``raypc probe`` does, in its JSON's shape:
        ``{"step", "time_myr", "level", "point": {...}, "values": {NAME: {"value", "units",
        "quantisation_error_max"}}}``."""
        return json.loads(self._core.probe(float(lat), float(lon), float(r_km), self._step(step), level,
                                           self._variable_name(variable) if variable else ""))

    def sample(self, step: StepLike = 0) -> "pd.DataFrame":
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

    def critical_points(self, step: StepLike = 0) -> "pd.DataFrame":
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
              level: int = 0, by: str = "step", mean_of: Optional[str] = None, progress: bool = True) -> "pd.DataFrame":
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
        if mean_of is not None:
            mean_of = self._variable_name(mean_of, "mean_of")
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
                 progress: bool = True) -> "pd.DataFrame":
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

    def map_grid(self, state: Union[None, State, dict, str, os.PathLike] = None, step: Optional[StepLike] = None,
                 variable: Optional[str] = None, depth_km: Optional[float] = None, grid_step_deg: float = 0) -> "xr.DataArray":
        """The state's map as an ``xarray.DataArray`` on (lat, lon): its colour variable (``variable``
        overrides) at its ``map.depthKm`` (``depth_km`` overrides, km below the surface) of ``step``
        (default: the state's), sampled every ``grid_step_deg`` degrees (0: 1°; must divide 180) as
        ``raypc map --netcdf`` writes it (trilinear on the native grid; NaN where the data have
        none), with CF attributes and units."""
        s = self._slice_state(state, step, variable)
        if depth_km is not None:
            s.setdefault("map", {})["depthKm"] = float(depth_km)
        return _grid_array(self._core.slice_grid(json.dumps(s), "map", float(grid_step_deg), 10.0))

    def section_grid(self, state: Union[None, State, dict, str, os.PathLike] = None, step: Optional[StepLike] = None,
                     variable: Optional[str] = None, start: Optional[tuple] = None, end: Optional[tuple] = None,
                     grid_step_deg: float = 0, depth_step_km: float = 10) -> "xr.DataArray":
        """The state's great-circle section as an ``xarray.DataArray`` on (depth km, distance km
        along the surface), with the latitude, longitude and angle of every column as auxiliary
        coordinates: its colour variable (``variable`` overrides) from ``start`` to ``end``
        ((lat, lon) degrees; default the state's ``section``), a column every ``grid_step_deg``
        (0: 0.5°) and a row every ``depth_step_km`` km, as ``raypc section --netcdf`` writes it."""
        s = self._slice_state(state, step, variable)
        section = s.setdefault("section", {})
        for key, point in (("from", start), ("to", end)):
            if point is not None:
                lat, lon = point
                section[key] = {"latDeg": float(lat), "lonDeg": float(lon)}
        return _grid_array(self._core.slice_grid(json.dumps(s), "section", float(grid_step_deg), float(depth_step_km)))

    def _slice_state(self, state: Any, step: Optional[StepLike], variable: Optional[str]) -> dict:
        s = _state_of(state, self).to_dict()
        if step is not None:
            s["step"] = self._step(step)
        if variable is not None:
            s.setdefault("color", {})["variable"] = variable
        return s

    def tracks(self, state: Union[None, State, dict, str, os.PathLike] = None, level: Optional[int] = None,
               min_volume_km3: Optional[float] = None, depths_km: Optional[Sequence[float]] = None,
               band_half_width_km: Optional[float] = None, min_overlap: Optional[float] = None,
               stall_by: Optional[str] = None, sigmas: float = 2.0, progress: bool = True) -> "FeatureTracks":
        """The features of the state's brushes followed through every step (docs/features.md): the
        tables of ``raypc features --tracks --events --stalls`` and ``raypc flux`` as DataFrames, the
        same numbers as the UI's Features panel. Needs the dataset's velocity (features are moved
        with the flow to link them). Settings left at None come from the state's ``features``:
        ``level``, ``min_volume_km3`` (km³), ``depths_km`` (the stall and flux depths, km),
        ``band_half_width_km`` (km), ``min_overlap`` (share of a feature's volume carried onto
        another for a link), ``stall_by`` ("mean-depth", "deepest" or "shallowest"); ``sigmas``:
        how far above its mean a shell's downward flux marks an avalanche step (standard
        deviations)."""
        import io

        import pandas as pd

        state = _state_of(state, self)
        settings = state.to_dict()["features"]
        pick = lambda value, key: settings[key] if value is None else value  # noqa: E731
        bar = _Progress("tracks", progress, delay=0.5)
        try:
            text = self._core.feature_series(
                state.to_json(None), int(pick(level, "level")), float(pick(min_volume_km3, "minVolumeKm3")),
                [float(d) for d in pick(depths_km, "depthsKm")], float(pick(band_half_width_km, "bandHalfWidthKm")),
                float(pick(min_overlap, "minOverlapShare")), str(pick(stall_by, "stallBy")), float(sigmas), bar)
        finally:
            bar.close()
        result = json.loads(text)
        tables = {name: (pd.read_csv(io.StringIO(csv)) if csv is not None else None)
                  for name, csv in result["csv"].items()}
        settings = {k: result[k] for k in ("level", "minVolumeKm3", "depthsKm", "bandHalfWidthKm", "minOverlapShare",
                                           "stallBy")}
        return FeatureTracks(tables["tracks"], tables["events"], tables["stalls"], tables["flux"], settings)

    # ---- other libraries ----------------------------------------------------------------------

    def to_vtk(self, step: StepLike = 0, variables: Optional[Sequence[str]] = None, level: int = 0) -> "vtkStructuredGrid":
        """A step as a ``vtkStructuredGrid`` (VTK's Python modules: Debian's python3-vtk9 or
        ParaView's): the native grid's points in km (x towards 0° E on the equator, z to the north
        pole), the longitude seam closed by repeating the first meridian, and every variable (or
        ``variables``) as point data with NaN where the data have none; units in the field data
        array ``units``."""
        try:
            from vtkmodules.util.numpy_support import numpy_to_vtk
            from vtkmodules.vtkCommonCore import vtkPoints, vtkStringArray
            from vtkmodules.vtkCommonDataModel import vtkStructuredGrid
        except ImportError as e:
            raise ImportError("to_vtk needs VTK's Python modules (Debian: apt install python3-vtk9)") from e
        s = self._step(step)
        names = [v.name for v in self._variables] if variables is None else (
            [variables] if isinstance(variables, str) else list(variables))
        g = self._levels[level]
        lon = np.append(g.lon, g.lon[0] + 360.0)  # the seam closed
        lat_r, r_r, lon_r = np.radians(g.lat), g.r, np.radians(lon)
        # Points in VTK's order: longitude fastest, then radius, then latitude (the values' (lat, r, lon)).
        la, rr, lo = np.meshgrid(lat_r, r_r, lon_r, indexing="ij")
        xyz = np.stack([rr * np.cos(la) * np.cos(lo), rr * np.cos(la) * np.sin(lo), rr * np.sin(la)], axis=-1)
        grid = vtkStructuredGrid()
        grid.SetDimensions(len(lon), len(g.r), len(g.lat))
        points = vtkPoints()
        points.SetData(numpy_to_vtk(np.ascontiguousarray(xyz.reshape(-1, 3)), deep=True))
        grid.SetPoints(points)
        units = vtkStringArray()
        units.SetName("units")
        for name in names:
            values = self.field(name, s, level).values
            closed = np.concatenate([values, values[:, :, :1]], axis=2)
            array = numpy_to_vtk(np.ascontiguousarray(closed.reshape(-1)), deep=True)
            array.SetName(name)
            grid.GetPointData().AddArray(array)
            units.InsertNextValue(f"{name}: {self._units[name]}")
        grid.GetFieldData().AddArray(units)
        return grid

    def to_pyvista(self, step: StepLike = 0, variables: Optional[Sequence[str]] = None, level: int = 0) -> Any:
        """A step as a ``pyvista.StructuredGrid`` (:meth:`to_vtk` wrapped by PyVista):
        ``ds.to_pyvista(6).plot(scalars="temperature anomaly")``."""
        try:
            import pyvista
        except ImportError as e:
            raise ImportError("to_pyvista needs PyVista (pip install pyvista); to_vtk gives the VTK grid without it") from e
        return pyvista.wrap(self.to_vtk(step, variables, level))

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
