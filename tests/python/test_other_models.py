"""Python's raypc on models that are not the contest's (tests/data: written by Python's netCDF4 and
h5py): a one-variable global tomography model, a regional one with a region of no data, and a CitcomS
run. Their variables, the computed shell anomalies, missing values kept missing and the region's
volume, as to_xarray, probe and stats give them."""
import json
import math
import os
from pathlib import Path

import numpy as np
import pytest

import raypc

DATA = Path(os.environ["RAYPC_TEST_DATA_DIR"])


def vs_formula(depth_km, lat_deg, lon_deg):
    """The EMC fixtures' vs (tests/data/emc-layout/write_emc_layout.py), km/s."""
    lat, lon = np.radians(lat_deg), np.radians(np.asarray(lon_deg) - 30.0)
    return 4.4 + 0.0007 * depth_km + 0.1 * np.cos(lat) * np.cos(lon) * (1.0 - depth_km / 2891.0)


@pytest.fixture(scope="module")
def regional(tmp_path_factory):
    out = tmp_path_factory.mktemp("regional") / "regional.raypc"
    return raypc.open(DATA / "emc-layout" / "regional_vs.nc", dataset=out, encoding="float32", progress=False)


@pytest.fixture(scope="module")
def global_vs(tmp_path_factory):
    out = tmp_path_factory.mktemp("global") / "global.raypc"
    return raypc.open(DATA / "emc-layout" / "global_vs.nc", dataset=out, encoding="float32", progress=False)


def test_a_tomography_model_has_its_variable_and_its_shell_anomalies(global_vs):
    x = global_vs.to_xarray(0)
    assert list(x.data_vars) == ["vs", "vs_anomaly", "vs_anomaly_percent"]  # CF names of the display names
    assert x["vs_anomaly_percent"].attrs.get("units") == "%"
    vs = x["vs"].values
    anomaly = x["vs_anomaly"].values
    # At every grid point: vs minus the area-weighted mean of its shell (weights: the dual cells'
    # sin(lat) band widths, every lon column alike here).
    lat = x["lat"].values
    edges = np.concatenate(([-90.0], (lat[1:] + lat[:-1]) / 2, [90.0]))
    w = np.diff(np.sin(np.radians(edges)))
    mean = np.einsum("l,lrk->r", w, vs) / (w.sum() * vs.shape[2])
    assert np.allclose(anomaly, vs - mean[None, :, None], atol=2e-5)
    assert np.allclose(x["vs_anomaly_percent"].values, 100 * (vs / mean[None, :, None] - 1), atol=5e-4)


def test_a_regional_model_keeps_no_data_missing(regional):
    x = regional.to_xarray(0)
    vs = x["vs"]
    lat, lon, r = x["lat"].values, x["lon"].values, x["radius"].values
    depth = 6371.0 - r
    inside = (lat[:, None, None] >= 20 - 1e-6) & (lat[:, None, None] <= 55 + 1e-6) \
        & (lon[None, None, :] >= 230 - 1e-6) & (lon[None, None, :] <= 295 + 1e-6)
    hole = (depth[None, :, None] > 400) & (lon[None, None, :] > 260 + 1e-6)
    data = np.broadcast_to(inside & ~hole, vs.shape)
    assert np.isnan(vs.values[~data]).all(), "a value where the file has none"
    assert np.isfinite(vs.values[data]).all(), "a value of the file lost"
    L, R, O = np.meshgrid(lat, depth, lon, indexing="ij")
    assert np.allclose(vs.values[data], vs_formula(R, L, O - 360.0)[data], atol=1e-5)


def test_probe_says_no_data_outside_the_region(regional):
    inside = regional.probe(37, -110, 6371 - 700, variable="vs")["values"]["vs"]
    assert math.isclose(inside["value"], float(vs_formula(700.0, 37.0, -110.0)), abs_tol=1e-5)
    outside = regional.probe(0, 0, 6000, variable="vs")["values"]["vs"]
    assert outside["value"] is None and outside["no_data"] is True
    hole = regional.probe(40, -80, 6371 - 600, variable="vs")["values"]["vs"]
    assert hole["value"] is None


def test_a_citcoms_run_opens_with_its_variables(tmp_path):
    run = raypc.open(DATA / "citcoms-layout", dataset=tmp_path / "citcoms.raypc", progress=False)
    names = set(run.to_xarray(0).data_vars)
    assert {"temperature", "viscosity"} <= names, names
    value = run.probe(30, 60, 5000, step=1, variable="temperature")["values"]["temperature"]["value"]
    c, r = math.radians(60), 5000 / 6371
    t = 0.5 + 0.2 * math.cos(c) + 0.1 * math.sin(c) * math.cos(math.radians(60)) + 0.3 * (1 - r) / 0.45 + 0.01
    assert abs(value - t) < 0.01
