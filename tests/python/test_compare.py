"""raypc.correlate, raypc.spectrum and raypc.degree_correlation (docs/compare.md) against the CLI's CSV
on fields of known spherical harmonics (tests/data/harmonics, written by Python's netCDF4 with its own
Legendre recurrence), and their CF coordinates."""
import csv
import io
import os
from pathlib import Path

import numpy as np
import pytest

import raypc
from conftest import run_cli

HARMONICS = Path(os.environ["RAYPC_TEST_DATA_DIR"]) / "harmonics"


@pytest.fixture(scope="module")
def sets(tmp_path_factory):
    """The fixture's global and regional files opened by raypc.open (float32 levels)."""
    out = tmp_path_factory.mktemp("harmonics")
    return {name: raypc.open(HARMONICS / f"{name}.nc", dataset=out / f"{name}.raypc", encoding="float32", progress=False)
            for name in ("global", "regional")}


def cli_table(*args):
    """The CSV a raypc command writes to -o, as rows of dicts (comment lines skipped)."""
    out = Path(os.environ.get("TMPDIR", "/tmp")) / f"raypc-compare-{os.getpid()}.csv"
    try:
        run_cli(*args, "-o", out)
        text = out.read_text()
    finally:
        out.unlink(missing_ok=True)
    return list(csv.DictReader(io.StringIO("".join(l for l in text.splitlines(True) if not l.startswith("#")))))


def floats(rows, column):
    return np.array([float(r[column]) if r[column] else np.nan for r in rows])


@pytest.mark.parametrize("lmax", [None, 4])
def test_correlate_equals_the_cli(sets, lmax):
    g = sets["global"].path
    c = raypc.correlate(sets["global"], g, "mix", "y20_holes", lmax=lmax)
    rows = cli_table("correlate", f"{g}:mix", f"{g}:y20_holes", *([] if lmax is None else ["--lmax", lmax]))
    assert c.sizes["depth"] == len(rows) == 5
    np.testing.assert_allclose(c.depth.values, floats(rows, "depth_km"), rtol=1e-8)
    for name in ("correlation", "rms_a", "rms_b", "rms_ratio", "area_covered_percent"):
        np.testing.assert_allclose(c[name].values, floats(rows, name), rtol=1e-8, err_msg=name)
    assert list(c.points.values) == [int(r["points"]) for r in rows]
    assert list(c.note.values) == [r["note"] for r in rows]
    # CF: depth in km, positive down, increasing; radius beside it.
    assert c.depth.attrs["units"] == "km" and c.depth.attrs["positive"] == "down"
    assert np.all(np.diff(c.depth.values) > 0)
    np.testing.assert_allclose(c.depth.values + c.radius.values, raypc.SURFACE_RADIUS_KM)
    if lmax is None:  # the Y(2,0) part of mix on the shells without missing values (orthogonal there)
        np.testing.assert_allclose(c.correlation.values[:3], 1 / np.sqrt(1.3125), rtol=1e-4)
        assert np.all(c.area_covered_percent.values[3:] < 95)
    else:  # filtered, the deep shells with missing values are left empty and say why
        assert np.isnan(c.correlation.values[-1]) and "the whole sphere" in c.note.values[-1]
        np.testing.assert_allclose(c.correlation.values[:3], 1.0, atol=1e-6)


def test_spectrum_equals_the_cli_and_the_truth(sets):
    g = sets["global"]
    s = raypc.spectrum(g, "mix", lmax=12)
    rows = cli_table("spectrum", f"{g.path}:mix", "--lmax", 12)
    assert s.dims == ("depth", "degree") and s.shape == (5, 13)
    np.testing.assert_allclose(s.values.ravel(), floats(rows, "power"), rtol=1e-8, atol=1e-30)
    assert [int(r["degree"]) for r in rows[:13]] == list(s.degree.values)
    np.testing.assert_allclose(s.depth.values, floats(rows, "depth_km")[::13])
    a2 = (s.radius.values / 1000.0) ** 2
    for degree, share in ((2, 1.0), (5, 0.25), (9, 0.0625)):
        np.testing.assert_allclose(s.sel(degree=degree).values, share * a2, rtol=1e-5)
    assert s.attrs["quadrature"] == "Fejér's first rule"
    assert s.depth.attrs["positive"] == "down"


def test_degree_correlation_equals_the_cli(sets):
    g = sets["global"]
    d = raypc.degree_correlation(g, g, 700, "mix", "mix_turned", lmax=10)
    rows = cli_table("spectrum", f"{g.path}:mix", "--with", f"{g.path}:mix_turned", "--depth", 700, "--lmax", 10)
    np.testing.assert_allclose(d.correlation.values, floats(rows, "correlation"), rtol=1e-8)
    np.testing.assert_allclose(d.power_a.values, floats(rows, "power_a"), rtol=1e-8, atol=1e-30)
    assert float(d.depth) == float(rows[0]["depth_km"]) == 771.0
    assert d.correlation.sel(degree=5) == pytest.approx(-1.0)


def test_refusals_name_the_reason(sets):
    with pytest.raises(raypc.Error, match="the grid is regional"):
        raypc.spectrum(sets["regional"], "y20")
    with pytest.raises(raypc.Error, match="missing values"):
        raypc.spectrum(sets["global"], "y20_holes")
    with pytest.raises(KeyError, match="no variable 'nope'"):
        raypc.correlate(sets["global"], sets["global"], "nope")
    with pytest.raises(raypc.Error, match="lmax"):
        raypc.correlate(sets["global"], sets["global"], "y20", "y20", lmax=-3)
    with pytest.raises(IndexError, match="out of range"):
        raypc.correlate(sets["global"], sets["global"], "y20", "y20", step=4)
    # A regional a: the correlation over its region, b resampled onto its grid.
    c = raypc.correlate(sets["regional"], sets["global"], "y20", "y20")
    assert c.attrs["b_resampled_onto_a_grid"] == 1
    np.testing.assert_allclose(c.correlation.values, 1.0, atol=1e-4)
    assert np.all(c.area_covered_percent.values < 10)
