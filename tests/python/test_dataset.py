"""raypc.open, Dataset's description, values (field, to_xarray, probe, sample), pathlines and
critical points, checked against the analytic truth of the contest-layout files and against the
raypc executable."""
import json
import math
import os
from pathlib import Path

import numpy as np
import pytest

import raypc
from conftest import CONTEST_LAYOUT, run_cli


def analytic(truth, name, t_myr, lat, r, lon):
    """The truth.json formulas at grid points (lat, r, lon), as the writer evaluates them."""
    LAT, R, LON = np.meshgrid(np.radians(lat), r, np.radians(lon), indexing="ij")
    p = np.stack([R * np.cos(LAT) * np.cos(LON), R * np.cos(LAT) * np.sin(LON), R * np.sin(LAT)])
    t_s = t_myr * 3.15576e13
    g = np.zeros_like(R)
    for lat0, lon0, r0, amp, sigma in truth["blobs_lat_lon_rkm_amp_sigma"]:
        lonc = math.radians(lon0) + truth["omega_rad_per_s"] * t_s
        rc = r0 + truth["u0_m_per_s"] * t_s / 1000.0
        c = np.array([rc * math.cos(math.radians(lat0)) * math.cos(lonc),
                      rc * math.cos(math.radians(lat0)) * math.sin(lonc), rc * math.sin(math.radians(lat0))])
        d2 = ((p - c[:, None, None, None]) ** 2).sum(axis=0)
        g += amp * np.exp(-d2 / (2 * sigma**2))
    anomaly = g - g.mean(axis=(0, 2), keepdims=True)
    if name == "temperature":
        return 300 + 3700 * (6371 - R) / (6371 - 3485) + anomaly
    if name == "thermal conductivity":
        return -1e-3 * anomaly
    raise KeyError(name)


def test_open_describes_the_dataset(contest, truth):
    names = [v.name for v in contest.variables]
    assert "temperature" in names and "radial velocity" in names and "temperature anomaly" in names
    units = {v.name: v.units for v in contest.variables}
    assert units["temperature"] == "K"
    assert list(contest.steps) == [0, 1, 2]
    np.testing.assert_allclose(contest.times, [0, 2, 4])
    g = truth["grid"]
    assert contest.grid.shape == (g["nlat"], g["nr"], g["nlon"])
    assert len(contest.levels) == 3
    assert contest.grid.depth[0] == pytest.approx(6371 - contest.grid.r[0])
    text = repr(contest)
    assert "3 steps" in text and "temperature [K]" in text and "36 lat x 41 r x 72 lon" in text


def test_open_reuses_the_finished_dataset(contest):
    files = sorted(CONTEST_LAYOUT.glob("spherical*.nc"))
    again = raypc.open(*files, dataset=contest.path, encoding="float32", sample_rows=2000, progress=False)
    assert again.path == contest.path


@pytest.mark.parametrize("name", ["temperature", "thermal conductivity"])
def test_field_equals_the_analytic_truth(contest, truth, name):
    for step in range(3):
        f = contest.field(name, step)
        assert f.values.shape == contest.grid.shape and f.values.dtype == np.float32
        assert f.step == step and f.time_myr == 2.0 * step
        expected = analytic(truth, name, f.time_myr, f.lat, f.r, f.lon)
        scale = np.abs(expected).max()
        assert np.abs(f.values - expected).max() <= 2e-6 * scale


def test_to_xarray_has_cf_coordinates_and_units(contest, truth):
    x = contest.to_xarray(1, variables=["temperature", "radial velocity"])
    assert set(x.data_vars) == {"temperature", "radial_velocity"}  # CF names (raypc.names.cf_name)
    assert x["radial_velocity"].attrs["long_name"] == "radial velocity"
    assert x["temperature"].dims == ("lat", "radius", "lon")
    assert x["lat"].attrs["units"] == "degrees_north" and x["lon"].attrs["units"] == "degrees_east"
    assert x["radius"].attrs["units"] == "km" and x["depth"].attrs["positive"] == "down"
    assert x["temperature"].attrs["units"] == "K"
    assert float(x["time"]) == 2.0 and x["time"].attrs["units"] == "Myr"
    shell = x["temperature"].sel(radius=5711, method="nearest")
    assert shell.dims == ("lat", "lon")
    i = int(np.abs(contest.grid.r - 5711).argmin())
    np.testing.assert_array_equal(shell.values, contest.field("temperature", 1).values[:, i, :])
    # radial velocity == u0 everywhere (5e-11 m/s = 0.1578 cm/yr)
    np.testing.assert_allclose(x["radial_velocity"].values, 5e-11 * 100 * 3.15576e7, rtol=1e-4)


@pytest.mark.parametrize("lat,lon,r", [(12.3, 45.6, 5000.0), (89.7, 123.0, 4000.0), (-89.9, 10.0, 6000.0),
                                      (5.0, 359.8, 3600.0), (5.0, -0.1, 3600.0)])
def test_probe_equals_the_cli(contest, lat, lon, r):
    mine = contest.probe(lat, lon, r, step=2)
    cli = json.loads(run_cli("probe", contest.path, "--time", 2, "--lat", lat, "--lon", lon, "--r", r).stdout)
    assert mine == cli
    assert mine["values"]["temperature"]["units"] == "K"


def test_probe_outside_the_shell_raises_the_cli_message(contest):
    with pytest.raises(raypc.Error, match=r"r_km: 3000 km is outside the mantle shell"):
        contest.probe(0, 0, 3000)
    with pytest.raises(raypc.Error, match="step: 7 out of range 0..2"):
        contest.field("temperature", 7)
    with pytest.raises(raypc.Error, match="unknown variable 'pressure'"):
        contest.field("pressure", 0)
    with pytest.raises(raypc.Error, match="variables: none given"):
        contest.to_xarray(0, variables=[])


def test_times_name_steps(contest):
    assert contest.field("temperature", "4Myr").step == 2


def test_sample_is_a_dataframe_with_units(contest):
    df = contest.sample(1)
    assert len(df) == 2000
    assert list(df.columns[:3]) == ["x", "y", "z"] or "lat" in df.columns
    assert "temperature" in df.columns and df.attrs["units"]["temperature"] == "K"
    assert df["depth"].between(0, 6371 - 3485).all()
    assert df["temperature"].between(contest.variables[0].min - 1e3, 1e5).all()


def test_pathlines_and_critical_points(contest):
    sets = contest.pathlines(2, window=10)
    assert [s["injection_step"] for s in sets] == [0, 1, 2] or len(sets) >= 1
    first = [s for s in sets if s["injection_step"] == 0][0]
    lines, points = first["lines"], first["points"]
    assert len(lines) > 0 and points["line"].max() == len(lines) - 1
    r = np.sqrt(points["x_km"] ** 2 + points["y_km"] ** 2 + points["z_km"] ** 2)
    assert r.between(3485 - 1, 6371 + 1).all()
    assert lines.attrs["units"]["length"] == "km"
    cps = contest.critical_points(0)
    assert len(cps) == len(lines)
    assert set(cps["kind"]) <= {"minimum", "1-saddle", "2-saddle", "maximum", "multi-saddle"}
    np.testing.assert_allclose(cps["depth_km"], 6371 - cps["radius_km"])
    assert cps.attrs["seed_field"] == "temperature anomaly"


ASPECT = Path(os.environ["RAYPC_SOURCE_DIR"]) / "tests" / "data" / "aspect-layout" / "shell-lagrange"


def test_open_an_aspect_series_with_progress(tmp_path, capsys):
    truth = json.loads((ASPECT / "truth.json").read_text())
    ds = raypc.open(ASPECT / "solution.pvd", dataset=tmp_path / "aspect.raypc", sample_rows=1000, no_pathlines=True)
    err = capsys.readouterr().err
    assert "preprocessing steps: [" in err and "2/2" in err
    np.testing.assert_allclose(ds.times, [0, 2])  # 2e6 years apart
    units = {v.name: v.units for v in ds.variables}
    assert units["T"] == "K" and units["radial velocity"] == "cm/yr"
    # T at a few points against the formula. The mesh is coarse (768 Q2 cells, ~400 km across at
    # the surface), so the 600 km blob's peak is 62 K low at its centre; elsewhere within ~10 K.
    for lat, lon, r in [(-30, 100, 4600), (35, 210, 5500), (0, 0, 5000), (80, 300, 4000)]:
        got = ds.probe(lat, lon, r, step=1, variable="T")["values"]["T"]["value"]
        t_years = 2e6
        blob = 0.0
        p = np.array([r * math.cos(math.radians(lat)) * math.cos(math.radians(lon)),
                      r * math.cos(math.radians(lat)) * math.sin(math.radians(lon)), r * math.sin(math.radians(lat))])
        for lat0, lon0, r0, amp, sigma in truth["blobs_lat_lon_rkm_amp_sigma"]:
            lonc = math.radians(lon0) + truth["omega_rad_per_year"] * t_years
            rc = r0 + truth["u0_m_per_year"] * t_years / 1000
            c = np.array([rc * math.cos(math.radians(lat0)) * math.cos(lonc),
                          rc * math.cos(math.radians(lat0)) * math.sin(lonc), rc * math.sin(math.radians(lat0))])
            blob += amp * math.exp(-((p - c) ** 2).sum() / (2 * sigma**2))
        expected = 1600 + 2000 * (6371 - r) / 2886 + blob
        assert abs(got - expected) < 80, (lat, lon, r, got, expected)


def test_open_refuses_with_the_cli_messages(tmp_path):
    with pytest.raises(raypc.Error, match="time_units 'days'"):
        raypc.open(ASPECT, dataset=tmp_path / "x", time_units="days", progress=False)
    with pytest.raises(raypc.Error, match="nowhere"):
        raypc.open(tmp_path / "nowhere", progress=False)
    with pytest.raises(raypc.Error, match="give a dataset"):
        raypc.open()
    with pytest.raises(raypc.Error, match="no_such_option"):
        raypc.open(ASPECT, no_such_option=3, progress=False)
    assert not (tmp_path / "x").exists()


def test_field_and_to_xarray_at_grid_points_equal_probe(contest):
    """At a grid point the interpolation is the point's own value: probe (the CLI's JSON) = field."""
    g = contest.grid
    f = contest.field("thermal conductivity", 2).values
    x = contest.to_xarray(2, ["thermal conductivity"])["thermal_conductivity"]
    for i, j, k in [(0, 0, 0), (17, 20, 71), (35, 40, 36), (5, 39, 1)]:
        value = contest.probe(g.lat[i], g.lon[k], g.r[j], step=2)["values"]["thermal conductivity"]["value"]
        assert value == pytest.approx(float(f[i, j, k]), rel=1e-6, abs=1e-9)
        assert float(x.isel(lat=i, radius=j, lon=k)) == float(f[i, j, k])


def test_an_interrupt_stops_preprocessing_and_the_next_open_resumes(tmp_path):
    files = sorted(str(p) for p in CONTEST_LAYOUT.glob("spherical*.nc"))
    calls = []

    def interrupt_after_the_first_step(phase, done, total):
        calls.append((phase, done, total))
        if done >= 1:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        raypc._raypc.prepare(files + ["--dataset", str(tmp_path / "ds"), "--no-pathlines"], interrupt_after_the_first_step)
    assert calls == [("steps", 0, 3), ("steps", 1, 3)]  # the steps done before the run, then the first one
    with pytest.raises(raypc.Error, match="not a complete|incomplete|unfinished"):
        raypc.Dataset(tmp_path / "ds")
    ds = raypc.open(*files, dataset=tmp_path / "ds", no_pathlines=True, progress=False)
    assert list(ds.steps) == [0, 1, 2]
