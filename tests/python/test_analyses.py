"""Every analysis from Python equals the command line's: features followed through the series
(Dataset.tracks: raypc features --tracks/--events/--stalls, raypc flux), maps and sections as
xarray DataArrays (raypc map/section --netcdf), a step as a VTK grid (to_vtk, to_pyvista); and the
notebook's short reprs."""
import json

import numpy as np
import pandas as pd
import pytest
import xarray as xr

import raypc
from conftest import run_cli

# Cold material in the upper mantle: features that the flow carries from step to step.
COLD = {"version": 12, "brushes": [{"name": "temperature anomaly", "min": -2000, "max": -60},
                                   {"name": "depth", "min": 100, "max": 1500}],
        "features": {"depthsKm": [660, 1000], "minVolumeKm3": 0, "stallBy": "deepest"}}


def test_tracks_equal_the_cli(contest, tmp_path):
    raypc.State(COLD).save(tmp_path / "cold.json")
    run_cli("features", contest.path, "--state", tmp_path / "cold.json", "-o", tmp_path / "f.csv",
            "--tracks", tmp_path / "t.csv", "--events", tmp_path / "e.csv", "--stalls", tmp_path / "s.csv", "--quiet")
    run_cli("flux", contest.path, "--state", tmp_path / "cold.json", "-o", tmp_path / "flux.csv",
            "--depth", 660, "--depth", 1000, "--quiet")
    mine = contest.tracks(COLD, progress=False)
    cli_tracks = pd.read_csv(tmp_path / "t.csv")
    assert len(cli_tracks) > 0 and mine.tracks["step"].nunique() == 3
    pd.testing.assert_frame_equal(mine.tracks, cli_tracks)
    pd.testing.assert_frame_equal(mine.events, pd.read_csv(tmp_path / "e.csv"))
    pd.testing.assert_frame_equal(mine.stalls, pd.read_csv(tmp_path / "s.csv"))
    pd.testing.assert_frame_equal(mine.flux, pd.read_csv(tmp_path / "flux.csv"))
    assert mine.settings["stallBy"] == "deepest" and mine.settings["depthsKm"] == [660, 1000]
    assert "tracks" in repr(mine) and len(repr(mine)) < 200
    # An argument overrides the state's setting, and a wrong one is named as Python names it.
    assert contest.tracks(COLD, stall_by="mean-depth", progress=False).settings["stallBy"] == "mean-depth"
    with pytest.raises(raypc.Error, match="^min_overlap: expected"):
        contest.tracks(COLD, min_overlap=2, progress=False)
    with pytest.raises(raypc.Error, match="no selection"):
        contest.tracks({"version": 12}, progress=False)


@pytest.mark.parametrize("view", ["map", "section"])
def test_map_and_section_grids_equal_the_cli(contest, tmp_path, view):
    state = {"version": 12, "step": 2, "color": {"variable": "temperature anomaly"},
             "map": {"depthKm": 1000}, "section": {"from": {"latDeg": -20, "lonDeg": 350}, "to": {"latDeg": 60, "lonDeg": 40}}}
    raypc.State(state).save(tmp_path / "s.json")
    run_cli(view, contest.path, "--state", tmp_path / "s.json", "-o", tmp_path / "cli.png", "--netcdf", tmp_path / "cli.nc")
    cli_file = xr.open_dataset(tmp_path / "cli.nc")
    cli = cli_file["temperature_anomaly"]
    mine = contest.map_grid(state) if view == "map" else contest.section_grid(state)
    assert mine.name == "temperature_anomaly" and mine.attrs["units"] == "K"
    assert mine.dims == cli.dims
    np.testing.assert_array_equal(mine.values, cli.values)
    for name in cli.coords:
        np.testing.assert_allclose(mine[name].values, cli[name].values, rtol=1e-12)
        assert mine[name].attrs.get("units") == cli[name].attrs.get("units")
    assert mine.attrs["title"] == cli_file.attrs["title"]
    assert ("1000 km depth" if view == "map" else "great-circle section") in mine.attrs["title"]


def test_map_grid_is_bilinear_between_grid_nodes(contest):
    # At a depth of the grid's own radii, trilinear sampling in the grid's coordinates is bilinear in
    # lat and lon between the four nodes around a point (across the seam too).
    g = contest.grid
    k = len(g.r) // 2
    f = contest.field("temperature", 1).values[:, k, :]
    m = contest.map_grid(step=1, variable="temperature", depth_km=float(raypc.SURFACE_RADIUS_KM - g.r[k]), grid_step_deg=1)
    dlon = g.lon[1] - g.lon[0]
    checked = 0
    for lat in (-60.5, -12.5, 0.5, 33.5, 79.5):
        for lon in (0.5, 101.5, 357.5, 359.5):
            i = np.searchsorted(g.lat, lat) - 1
            u = (lat - g.lat[i]) / (g.lat[i + 1] - g.lat[i])
            j = int(lon // dlon)
            v = (lon - g.lon[j]) / dlon
            j1 = (j + 1) % len(g.lon)
            expected = ((1 - u) * ((1 - v) * f[i, j] + v * f[i, j1]) + u * ((1 - v) * f[i + 1, j] + v * f[i + 1, j1]))
            np.testing.assert_allclose(m.sel(lat=lat, lon=lon).item(), expected, rtol=1e-5)
            checked += 1
    assert checked == 20
    # Overrides: the depth and the section's ends; bad spacings named as Python names them.
    s = contest.section_grid(step=1, start=(0, 10), end=(0, 100), grid_step_deg=1)
    assert s.lat.values[0] == pytest.approx(0, abs=1e-9) and s.lon.values[-1] == pytest.approx(100)
    assert s.dims == ("depth", "distance") and s.distance.attrs["units"] == "km"
    with pytest.raises(raypc.Error, match="grid_step_deg 7: expected degrees that divide 180"):
        contest.map_grid(grid_step_deg=7)
    with pytest.raises(raypc.Error, match="depth_step_km 0.01: at least 0.1 km"):
        contest.section_grid(depth_step_km=0.01)


def test_to_vtk_is_the_native_grid_with_the_seam_closed(contest):
    vtk = pytest.importorskip("vtkmodules.util.numpy_support",
                              reason="VTK's Python modules are not installed (Debian: python3-vtk9 or python3-paraview)")
    g = contest.grid
    grid = contest.to_vtk(2, ["temperature", "temperature anomaly"])
    dims = [0, 0, 0]
    grid.GetDimensions(dims)
    assert dims == [len(g.lon) + 1, len(g.r), len(g.lat)]
    points = vtk.vtk_to_numpy(grid.GetPoints().GetData()).reshape(len(g.lat), len(g.r), len(g.lon) + 1, 3)
    i, k, j = 1, len(g.r) - 1, 3
    lat, lon = np.radians(g.lat[i]), np.radians(g.lon[j])
    expected = g.r[k] * np.array([np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon), np.sin(lat)])
    np.testing.assert_allclose(points[i, k, j], expected, rtol=1e-9)
    np.testing.assert_allclose(points[:, :, -1], points[:, :, 0], atol=1e-6)  # the seam closed
    t = vtk.vtk_to_numpy(grid.GetPointData().GetArray("temperature")).reshape(len(g.lat), len(g.r), len(g.lon) + 1)
    f = contest.field("temperature", 2).values
    np.testing.assert_array_equal(t[:, :, :-1], f)
    np.testing.assert_array_equal(t[:, :, -1], f[:, :, 0])
    assert grid.GetPointData().GetNumberOfArrays() == 2


def test_to_pyvista(contest):
    pv = pytest.importorskip("pyvista", reason="PyVista is not installed (not packaged by Debian 12)")
    grid = contest.to_pyvista(0, "temperature")
    assert isinstance(grid, pv.StructuredGrid) and "temperature" in grid.point_data


def test_notebook_reprs(contest):
    html = contest._repr_html_()
    for v in contest.variables:
        assert f">{v.name}<" in html.replace("&#x27;", "'")
    assert f"{len(contest.steps)} steps" in html
    f = contest.field("temperature", 1)
    text = repr(f)
    assert len(text) < 200 and "'temperature'" in text and "K" in text
    lo, hi = np.nanmin(f.values), np.nanmax(f.values)
    assert f"{lo:.6g}..{hi:.6g} K" in text
    assert len(repr(contest.grid)) < 200 and "km" in repr(contest.grid)
