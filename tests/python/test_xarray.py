"""The xarray backend (raypc.xarray_backend): the whole series as one lazy Dataset with CF names,
checked against Dataset.field and the contest-layout truth; what it reads (the compiled module's
count of grid values read), selection by depth and radius, dask chunks, a netCDF round trip."""
import numpy as np
import pytest
import xarray as xr

import raypc
from conftest import CONTEST_LAYOUT
from raypc._raypc import values_read
from raypc.names import cf_name, cf_names
from raypc.xarray_backend import RaypcBackendEntrypoint
from test_dataset import analytic

ENGINE = "raypc"  # the entry point: pip's metadata when installed, build/python's dist-info in the build tree


@pytest.fixture(scope="module")
def contest_u16(tmp_path_factory):
    """The contest files as u16 levels: reading a box decodes points alone (decodeUint16Point),
    which must give the bits of decoding the whole step."""
    out = tmp_path_factory.mktemp("contest-u16") / "contest.raypc"
    files = sorted(CONTEST_LAYOUT.glob("spherical*.nc"))
    return raypc.open(*files, dataset=out, encoding="u16", sample_rows=2000, no_pathlines=True, progress=False)


@pytest.fixture(scope="module")
def regional(tmp_path_factory):
    """A regional model: missing values (NaN) outside its region."""
    data = CONTEST_LAYOUT.parent / "emc-layout" / "regional_vs.nc"
    out = tmp_path_factory.mktemp("regional") / "regional.raypc"
    return raypc.open(data, dataset=out, encoding="float32", no_pathlines=True, progress=False)


def nearest(values, target):
    return int(np.abs(np.asarray(values) - target).argmin())


def test_cf_names_are_safe_and_unique():
    assert cf_name("temperature anomaly %") == "temperature_anomaly_percent"
    assert cf_name("Thermal  Conductivity") == "Thermal_Conductivity" and cf_name("dlnVs") == "dlnVs"  # case kept
    assert cf_name("3d field") == "v_3d_field"
    assert cf_names(["a b", "a_b", "A B %"]) == {"a b": "a_b", "a_b": "a_b_2", "A B %": "A_B_percent"}


def test_opening_reads_no_values_and_describes_the_series(contest):
    before = values_read()
    x = xr.open_dataset(contest.path, engine=ENGINE)
    assert values_read() == before, "opening read values"
    g = contest.grid
    assert dict(x.sizes) == {"time": len(contest.steps), "lat": len(g.lat), "radius": len(g.r), "lon": len(g.lon)}
    np.testing.assert_array_equal(x.time.values, contest.times)
    assert x.time.attrs["units"] == "Myr" and x.time.attrs["standard_name"] == "time"
    np.testing.assert_array_equal(x.depth.values, g.depth)
    assert x.attrs["Conventions"] == "CF-1.8" and x.attrs["level"] == 0
    expected = {cf_name(v.name): v for v in contest.variables}
    assert set(x.data_vars) == set(expected)
    for name, v in expected.items():
        assert " " not in name and "%" not in name
        assert x[name].attrs["long_name"] == v.name
        assert x[name].attrs.get("units", "") == v.units
        assert x[name].dims == ("time", "lat", "radius", "lon")
    assert x.temperature_anomaly.attrs["long_name"] == "temperature anomaly"
    assert "temperature_anomaly_percent" in x
    assert values_read() == before, "describing the Dataset read values"


@pytest.mark.parametrize("which", ["contest", "contest_u16"])
@pytest.mark.parametrize("name", ["temperature", "temperature anomaly", "temperature anomaly %"])
def test_one_shell_of_one_step_reads_only_that_shell(request, which, name):
    ds = request.getfixturevalue(which)
    x = xr.open_dataset(ds.path, engine=ENGINE)
    g = ds.grid
    before = values_read()
    shell = x[cf_name(name)].sel(depth=660, method="nearest").isel(time=-1).values
    read = values_read() - before
    # One shell of one step (a shell anomaly: its base on that shell, for the shell's mean).
    assert read == len(g.lat) * len(g.lon), read
    i = nearest(g.depth, 660)
    np.testing.assert_array_equal(shell, ds.field(name, ds.steps[-1]).values[:, i, :])


def test_a_point_over_time_reads_a_value_per_step(contest):
    x = xr.open_dataset(contest.path, engine=ENGINE)
    before = values_read()
    series = x.temperature.sel(depth=1000, method="nearest").isel(lat=5, lon=7).values
    assert values_read() - before == len(contest.steps)
    i = nearest(contest.grid.depth, 1000)
    np.testing.assert_array_equal(series, [contest.field("temperature", s).values[5, i, 7] for s in contest.steps])


def test_sel_by_depth_and_by_radius_agree(contest):
    x = xr.open_dataset(contest.path, engine=ENGINE)
    by_depth = x.thermal_conductivity.sel(depth=660, method="nearest")
    by_radius = x.thermal_conductivity.sel(radius=6371 - 660, method="nearest")
    assert float(by_depth.radius) == float(by_radius.radius)
    assert float(by_depth.depth) == pytest.approx(6371 - float(by_depth.radius))
    np.testing.assert_array_equal(by_depth.values, by_radius.values)


@pytest.mark.parametrize("which", ["contest", "contest_u16"])
def test_every_variable_and_box_equals_field(request, which):
    """Whole steps and boxes (strided, reversed, a single point) of every variable, derived ones
    included, equal Dataset.field's values of the same step, bit for bit."""
    ds = request.getfixturevalue(which)
    x = xr.open_dataset(ds.path, engine=ENGINE)
    boxes = [dict(lat=slice(3, 9), radius=slice(5, 7), lon=slice(60, 70, 3)),
             dict(lat=slice(None, None, -5), radius=[0, 40, 20], lon=3),
             dict(lat=0, radius=0, lon=0)]
    for v in ds.variables:
        for step in ds.steps:
            f = ds.field(v.name, step).values
            whole = x[cf_name(v.name)].isel(time=step)
            np.testing.assert_array_equal(whole.values, f, err_msg=f"{v.name} step {step}")
            for box in boxes:
                got = whole.isel(box).values
                reference = xr.DataArray(f, dims=("lat", "radius", "lon")).isel(box).values
                np.testing.assert_array_equal(got, reference, err_msg=f"{v.name} step {step} {box}")


def test_values_equal_the_analytic_truth(contest, truth):
    x = xr.open_dataset(contest.path, engine=ENGINE)
    for step in contest.steps:
        t = x.temperature.isel(time=step)
        expected = analytic(truth, "temperature", float(t.time), x.lat.values, x.radius.values, x.lon.values)
        assert np.abs(t.values - expected).max() <= 2e-6 * np.abs(expected).max()


def test_to_xarray_is_the_lazy_series_and_one_step_of_it(contest):
    series = contest.to_xarray()
    opened = xr.open_dataset(contest.path, engine=ENGINE)
    assert list(series.data_vars) == list(opened.data_vars)
    before = values_read()
    one = contest.to_xarray(1, ["temperature", "radial_velocity"])  # display and CF names
    assert values_read() == before
    assert set(one.data_vars) == {"temperature", "radial_velocity"}
    assert one.attrs["step"] == 1 and float(one.time) == contest.times[1]
    np.testing.assert_array_equal(one.radial_velocity.values, contest.field("radial velocity", 1).values)
    np.testing.assert_array_equal(contest.field("temperature_anomaly", 1).values,
                                  contest.field("temperature anomaly", 1).values)


def test_drop_variables_and_level(contest):
    x = xr.open_dataset(contest.path, engine=ENGINE, drop_variables=["temperature anomaly %", "temperature", "nothing"])
    assert "temperature" not in x and "temperature_anomaly_percent" not in x and "temperature_anomaly" in x
    coarse = xr.open_dataset(contest.path, engine=ENGINE, level=1)
    g1 = contest.levels[1]
    assert coarse.sizes["radius"] == len(g1.r) and coarse.attrs["level"] == 1
    np.testing.assert_array_equal(coarse.temperature_anomaly.isel(time=2).sel(depth=660, method="nearest").values,
                                  contest.field("temperature anomaly", 2, level=1).values[:, nearest(g1.depth, 660), :])
    with pytest.raises(IndexError, match=r"level: 7 out of range 0\.\.2"):  # raypc.OutOfRangeError
        xr.open_dataset(contest.path, engine=ENGINE, level=7)
    with pytest.raises(TypeError, match="level: expected an integer level of detail, not 1.5"):
        xr.open_dataset(contest.path, engine=ENGINE, level=1.5)
    with pytest.raises(KeyError, match="unknown variable 'pressure'"):  # raypc.UnknownNameError
        contest.to_xarray(0, ["pressure"])
    with pytest.raises(raypc.Error, match="unknown variable 'pressure'"):
        contest.to_xarray(0, ["pressure"])
    with pytest.raises(raypc.Error, match=r"read_box: r index range 3\.\.3 is empty"):
        contest._core.read_box("temperature", 0, 0, [0, 3, 0], [1, 3, 1])


def test_the_engine_is_found_by_its_name(contest):
    from importlib.metadata import entry_points

    (ep,) = [e for e in entry_points(group="xarray.backends") if e.name == "raypc"]
    assert ep.load() is RaypcBackendEntrypoint
    by_name = xr.open_dataset(contest.path, engine="raypc")
    assert by_name.identical(xr.open_dataset(contest.path, engine=RaypcBackendEntrypoint).assign_attrs(
        history=by_name.attrs["history"]))
    # xarray picks the engine itself for a dataset directory (guess_can_open)
    assert set(xr.open_dataset(contest.path).data_vars) == set(by_name.data_vars)


def test_guess_can_open(contest, tmp_path):
    entry = RaypcBackendEntrypoint()
    assert entry.guess_can_open(contest.path) and entry.guess_can_open(str(contest.path))
    assert not entry.guess_can_open(tmp_path)
    assert not entry.guess_can_open(sorted(CONTEST_LAYOUT.glob("spherical*.nc"))[0])


def test_dask_chunks_are_one_step_of_one_variable(contest):
    pytest.importorskip("dask", reason="dask is not installed (Debian: python3-dask)")
    g = contest.grid
    for chunks in ({}, {"time": 1}):
        x = xr.open_dataset(contest.path, engine=ENGINE, chunks=chunks)
        assert x.temperature.chunks == ((1,) * len(contest.steps), (len(g.lat),), (len(g.r),), (len(g.lon),))
    before = values_read()
    mean = x.temperature_anomaly.sel(depth=660, method="nearest").mean(("lat", "lon"))
    assert values_read() == before, "building the graph read values"
    values = mean.compute().values
    assert values_read() - before == len(contest.steps) * len(g.lat) * len(g.lon)
    i = nearest(g.depth, 660)
    expected = [contest.field("temperature anomaly", s).values[:, i, :].astype(np.float64).mean() for s in contest.steps]
    np.testing.assert_allclose(values, expected, rtol=1e-5, atol=1e-3)


def test_netcdf_round_trip_keeps_names_values_and_missing(regional, tmp_path):
    netCDF4 = pytest.importorskip("netCDF4")
    x = xr.open_dataset(regional.path, engine=ENGINE)
    out = tmp_path / "regional.nc"
    x.to_netcdf(out)
    y = xr.open_dataset(out)  # the default engine
    assert list(y.data_vars) == list(x.data_vars)
    assert y.time.dtype == np.float64 and y.time.attrs["units"] == "Myr", "time decoded as dates or durations"
    for name in x.data_vars:
        assert y[name].attrs["long_name"] == x[name].attrs["long_name"]
        assert y[name].attrs.get("units") == x[name].attrs.get("units")
        np.testing.assert_array_equal(y[name].values, x[name].values)  # NaN where missing, alike
    assert np.isnan(y.vs.values).any() and np.isfinite(y.vs.values).any()
    np.testing.assert_array_equal(y.depth.values, x.depth.values)
    for key in ("Conventions", "source", "level"):
        assert y.attrs[key] == x.attrs[key]
    with netCDF4.Dataset(out) as nc:
        for name in list(nc.variables) + list(nc.dimensions):
            assert name.replace("_", "").isalnum() and name[0].isalpha(), name
        assert nc.variables["vs"].coordinates.split() == ["depth"]
