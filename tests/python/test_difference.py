"""raypc.diff (docs/compare.md, "Differences"): the difference dataset the CLI writes, as xarray with
CF coordinates; its numbers equal `raypc diff`'s and the analytic difference; refusals are raypc.Error."""
import shutil

import netCDF4
import numpy as np
import pytest
import xarray as xr

import raypc
from conftest import CONTEST_LAYOUT, run_cli


@pytest.fixture(scope="module")
def pair(tmp_path_factory):
    """A: the contest-layout files; B: the same with c = 30 cos(lat) cos(lon) K added to the temperature
    (written with netCDF4). Both preprocessed by the executable."""
    tmp = tmp_path_factory.mktemp("difference")
    files = sorted(CONTEST_LAYOUT.glob("spherical*.nc"))
    (tmp / "b").mkdir()
    for f in files:
        out = tmp / "b" / f.name
        shutil.copy(f, out)
        with netCDF4.Dataset(out, "r+") as nc:
            lat = np.radians(nc["lat"][:])[:, None, None]
            lon = np.radians(nc["lon"][:])[None, None, :]
            nc["temperature"][:] = nc["temperature"][:] + (30 * np.cos(lat) * np.cos(lon)).astype(np.float32)
    for name, inputs in (("a.ds", files), ("b.ds", sorted((tmp / "b").glob("*.nc")))):
        run_cli("preprocess", *inputs, "-o", tmp / name, "-q", "--no-pathlines", "--sample-rows", "500")
    return tmp


def test_diff_equals_the_cli_and_the_analytic_difference(pair):
    x = raypc.diff(pair / "a.ds", pair / "b.ds", pair / "py.ds", progress=False)
    run_cli("diff", pair / "a.ds", pair / "b.ds", "-o", pair / "cli.ds", "-q")
    cli = xr.open_dataset(pair / "cli.ds", engine="raypc")
    assert set(x.data_vars) == set(cli.data_vars)
    for name in x.data_vars:
        np.testing.assert_array_equal(x[name].values, cli[name].values, err_msg=name)
    # CF coordinates, names and units kept, what it is the difference of said.
    assert x.lat.attrs["standard_name"] == "latitude" and x.depth.attrs["units"] == "km"
    assert list(x.time.values) == [0.0, 2.0, 4.0]
    assert x.temperature.attrs["units"] == "K"
    assert x.temperature.attrs["comment"] == "temperature of a.ds − b.ds"
    assert '"match": "index"' in x.attrs["raypc_difference"]
    # −c at the grid points, every other stored variable 0. A and B are u16: each temperature within its
    # brick's range / 131070 (bricks spanning up to ~2000 K here) of the file's, so D within ~0.03 K.
    lat = np.radians(x.lat.values)[None, :, None, None]
    lon = np.radians(x.lon.values)[None, None, None, :]
    assert float(np.abs(x.temperature.values + 30 * np.cos(lat) * np.cos(lon)).max()) < 0.05
    assert float(np.abs(x.vx.values).max()) == 0


def test_step_differences_and_chosen_variables(pair):
    x = raypc.diff(pair / "a.ds", None, pair / "steps.ds", variables=["temperature"], steps=1, progress=False)
    run_cli("diff", pair / "a.ds", "--steps", "1", "--variable", "temperature", "-o", pair / "steps-cli.ds", "-q")
    cli = xr.open_dataset(pair / "steps-cli.ds", engine="raypc")
    assert list(x.time.values) == [2.0, 4.0]
    assert "vx" not in x.data_vars and "temperature" in x.data_vars
    np.testing.assert_array_equal(x.temperature.values, cli.temperature.values)
    a = xr.open_dataset(pair / "a.ds", engine="raypc")
    # X(t) − X(t−1), within the u16 quantisation of A's and of D's values.
    want = a.temperature.values[1:] - a.temperature.values[:-1]
    assert float(np.abs(x.temperature.values - want).max()) < 0.1


def test_refusals_are_raypc_errors(pair):
    with pytest.raises(raypc.OutOfRangeError, match=r"steps: 3 out of range 1\.\.2 \(a\.ds has 3 steps\)"):
        raypc.diff(pair / "a.ds", None, pair / "x.ds", steps=3, progress=False)
    with pytest.raises(raypc.Error, match="match: 'nearest', expected 'index' or 'time'"):
        raypc.diff(pair / "a.ds", pair / "b.ds", pair / "x.ds", match="nearest", progress=False)
    with pytest.raises(raypc.UnknownNameError, match="variable 'pressure': a.ds has no such variable"):
        raypc.diff(pair / "a.ds", pair / "b.ds", pair / "x.ds", variables=["pressure"], progress=False)
    with pytest.raises(raypc.Error, match="not both"):
        raypc.diff(pair / "a.ds", pair / "b.ds", pair / "x.ds", steps=1, progress=False)
    assert not (pair / "x.ds").exists()
