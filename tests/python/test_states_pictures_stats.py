"""raypc.State (the one state schema, its messages), Dataset.render (bit for bit raypc render) and
Dataset.stats (raypc stats' figures), and that long work runs without the GIL."""
import json
import threading
import time

import numpy as np
import pandas as pd
import pytest
from PIL import Image

import raypc
from conftest import run_cli

BRUSHED = {
    "step": 1,
    "image": {"width": 160, "height": 120},
    "color": {"variable": "temperature anomaly", "colorMap": "blue-white-red", "range": [-300, 300]},
    "brushes": [{"name": "depth", "min": 500, "max": 1500}, {"name": "temperature anomaly", "min": 20, "max": 1000}],
    "passes": 3,
    "legend": True,
    "reference": {"shells": {"visible": True}},
}


@pytest.mark.parametrize("bad", [{"step": "three"}, {"brushes": [{"name": "depth", "min": 1}]},
                                 {"camera": {"fovYDeg": 500}}, {"colour": {}}])
def test_state_checks_with_the_schemas_messages(contest, tmp_path, bad):
    (tmp_path / "bad.json").write_text(json.dumps(dict(bad, version=raypc.STATE_VERSION)))
    with pytest.raises(raypc.Error) as caught:
        raypc.State(bad)
    cli = run_cli("render", contest.path, "--state", tmp_path / "bad.json", "-o", tmp_path / "x.png", check=False)
    assert cli.returncode != 0 and not (tmp_path / "x.png").exists()
    message = str(caught.value)
    assert message.split(": ", 1)[1] in cli.stderr, (message, cli.stderr)


def test_state_attributes_edit_and_validate():
    s = raypc.State(BRUSHED)
    assert s.step == 1 and s.color["variable"] == "temperature anomaly"
    s.step = 2
    assert s.step == 2
    s.brushes.append({"name": "lat", "min": -10, "max": 10})
    assert [b["name"] for b in s.validate().brushes] == ["depth", "temperature anomaly", "lat"]
    with pytest.raises(raypc.Error):
        s.passes = -1
    assert s.passes == 3  # a refused change leaves the state as it was
    s.brushes.append({"name": "lat", "min": 5, "max": -5})
    with pytest.raises(raypc.Error, match="min"):
        s.validate()
    with pytest.raises(AttributeError, match="no field 'colour'"):
        s.colour
    assert "brushes=[depth 500..1500" in repr(raypc.State(BRUSHED))


def test_state_from_file_text_and_state(tmp_path):
    path = tmp_path / "s.json"
    raypc.State(BRUSHED).save(path)
    assert raypc.State(path) == raypc.State(BRUSHED)
    assert raypc.State(path.read_text()) == raypc.State(str(path))
    with pytest.raises(raypc.Error, match="cannot read"):
        raypc.State(tmp_path / "missing.json")


def test_check_state_against_the_dataset(contest):
    with pytest.raises(raypc.Error, match="step: 9 out of range 0..2"):
        contest.check_state(dict(BRUSHED, step=9))
    with pytest.raises(raypc.Error, match="pressure"):
        contest.check_state(dict(BRUSHED, brushes=[{"name": "pressure", "min": 0, "max": 1}]))


@pytest.mark.parametrize("state", [None, BRUSHED])
def test_render_equals_the_cli_bit_for_bit(contest, tmp_path, state):
    args = ["render", contest.path, "-o", tmp_path / "cli.png"]
    if state is None:
        args += ["--size", "160x120"]
        picture = contest.render(size=(160, 120))
    else:
        raypc.State(state).save(tmp_path / "s.json")
        args += ["--state", tmp_path / "s.json"]
        picture = contest.render(raypc.State(state))
    run_cli(*args)
    cli = np.asarray(Image.open(tmp_path / "cli.png").convert("RGB"))
    assert isinstance(picture, raypc.Picture) and picture.shape == (120, 160, 4) and picture.dtype == np.uint8
    np.testing.assert_array_equal(np.asarray(picture)[..., :3], cli)
    assert picture._repr_png_().startswith(b"\x89PNG")
    # the picture shows something: not one flat colour
    assert len(np.unique(cli.reshape(-1, 3), axis=0)) > 20


@pytest.mark.parametrize("view", ["map", "section"])
def test_map_and_section_equal_the_cli_bit_for_bit(contest, tmp_path, view):
    state = dict(BRUSHED, image={"width": 320, "height": 200}, version=9,
                 map={"depthKm": 1000, "projection": "robinson", "contours": [0]},
                 section={"from": {"latDeg": -20, "lonDeg": 40}, "to": {"latDeg": 60, "lonDeg": 40}})
    raypc.State(state).save(tmp_path / "s.json")
    run_cli(view, contest.path, "--state", tmp_path / "s.json", "-o", tmp_path / "cli.png")
    cli = np.asarray(Image.open(tmp_path / "cli.png").convert("RGB"))
    picture = contest.render(state, view=view)
    assert picture.shape == (200, 320, 4)
    np.testing.assert_array_equal(np.asarray(picture)[..., :3], cli)
    assert len(np.unique(cli.reshape(-1, 3), axis=0)) > 20
    with pytest.raises(raypc.Error, match="view 'globe'"):
        contest.render(state, view="globe")


def test_render_overrides_and_refuses(contest):
    a = contest.render(BRUSHED, step=0, passes=1)
    b = contest.render(BRUSHED, step=2, passes=1)
    assert a.shape == b.shape and not np.array_equal(a, b)
    with pytest.raises(raypc.Error, match="step"):
        contest.render(BRUSHED, step=5)
    with pytest.raises(raypc.Error, match="image.width"):
        contest.render(BRUSHED, size=(0, 10))
    # A long string that is not JSON (taken for a path) is not quoted whole in the message.
    with pytest.raises(raypc.Error, match="200000 characters") as refused:
        contest.render("x" * 200_000)
    assert len(str(refused.value)) < 300


def test_stats_equal_the_cli(contest, tmp_path):
    raypc.State(BRUSHED).save(tmp_path / "s.json")
    run_cli("stats", contest.path, "--state", tmp_path / "s.json", "-o", tmp_path / "stats.csv", "--profile",
            tmp_path / "profile.csv", "--quiet")
    cli = pd.read_csv(tmp_path / "stats.csv")
    mine = contest.stats(BRUSHED, progress=False)
    assert list(mine.columns) == list(cli.columns)
    assert (mine["selected_volume_km3"] > 0).all()
    pd.testing.assert_frame_equal(mine, cli, check_exact=False, rtol=1e-6, check_dtype=False)
    cli_profile = pd.read_csv(tmp_path / "profile.csv")
    profile = contest.stats(BRUSHED, by="depth", progress=False)
    assert list(profile.columns) == list(cli_profile.columns)
    pd.testing.assert_frame_equal(profile, cli_profile, check_exact=False, rtol=1e-6, atol=1e-3, check_dtype=False)
    # The means per depth (mean_of, the CLI's --profile-var): the same columns and numbers.
    run_cli("stats", contest.path, "--state", tmp_path / "s.json", "-o", tmp_path / "stats.csv", "--profile",
            tmp_path / "means.csv", "--profile-var", "temperature anomaly", "--quiet")
    cli_means = pd.read_csv(tmp_path / "means.csv")
    means = contest.stats(BRUSHED, by="depth", mean_of="temperature anomaly", progress=False)
    assert list(means.columns) == list(cli_means.columns)
    selected = "temperature anomaly selected mean [K]"
    assert means[selected].notna().any() and means[selected].isna().any()  # rows with and without a selection
    pd.testing.assert_frame_equal(means, cli_means, check_exact=False, rtol=1e-6, atol=1e-3, check_dtype=False)
    with pytest.raises(raypc.Error, match="mean_of: unknown variable 'pressure'"):
        contest.stats(BRUSHED, by="depth", mean_of="pressure", progress=False)
    with pytest.raises(raypc.Error, match="by='depth'"):
        contest.stats(BRUSHED, mean_of="temperature anomaly", progress=False)
    one = contest.stats(BRUSHED, steps=(1, 2), progress=False)
    assert list(one["step"]) == [1, 2]
    with pytest.raises(raypc.Error, match="by"):
        contest.stats(BRUSHED, by="year")


def test_features_equal_the_cli(contest, tmp_path):
    caps = {"version": 4, "brushes": [{"name": "depth", "min": 0, "max": 660}, {"name": "lat", "min": -90, "max": -60},
                                      {"name": "lat", "min": 60, "max": 90}]}
    raypc.State(caps).save(tmp_path / "caps.json")
    run_cli("features", contest.path, "--state", tmp_path / "caps.json", "-o", tmp_path / "f.csv", "--depth", 300,
            "--quiet")
    cli = pd.read_csv(tmp_path / "f.csv")
    mine = contest.features(caps, depths_km=[300], progress=False)
    pd.testing.assert_frame_equal(mine, cli)
    assert list(mine.groupby("step").size()) == [2, 2, 2], "two polar caps a step"
    assert "temperature mean [K]" in mine.columns and "percent_within_50km_of_300km" in mine.columns
    assert list(contest.features(caps, steps=1, progress=False)["step"]) == [1, 1]
    with pytest.raises(raypc.Error, match="no brushes"):
        contest.features({"version": 4}, progress=False)
    # The arguments are checked as a state's features are, and named as Python names them.
    for bad in ({"min_volume_km3": float("nan")}, {"depths_km": [-5]}, {"band_half_width_km": 1e30}):
        with pytest.raises(raypc.Error, match=f"^{next(iter(bad))}: expected"):
            contest.features(caps, progress=False, **bad)
    # The state's feature settings (version 10) stand for the arguments left out.
    saved = dict(caps, version=10, features={"depthsKm": [300], "minVolumeKm3": 0})
    pd.testing.assert_frame_equal(contest.features(saved, progress=False), cli)


def test_render_and_stats_release_the_gil(contest):
    """Python keeps running while a picture renders on the other threads."""
    counted = 0
    done = threading.Event()

    def count():
        nonlocal counted
        while not done.is_set():
            counted += 1

    counter = threading.Thread(target=count)
    counter.start()
    start = time.monotonic()
    contest.render(BRUSHED, size=(480, 360), passes=6)
    seconds = time.monotonic() - start
    done.set()
    counter.join()
    # With the GIL held for the whole render the counter could run only in the interpreter's
    # switch intervals (5 ms) around the call; released, it runs throughout.
    assert counted > 20000 * seconds, (counted, seconds)
