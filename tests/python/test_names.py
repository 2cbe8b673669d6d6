"""src/grid/names.json, read here from the source tree, against what the program writes: the derived
variables of a preprocessed dataset, the CSV headers of `raypc stats` and `raypc export`, and the
columns of Python's DataFrames. The C++ constants, the UI and Python all take their names from the
table, so a test that compares one of them with another cannot see the table drift from an output;
this one compares the outputs with the table itself.
"""
import csv
import json
import os
from pathlib import Path

import raypc
from conftest import run_cli

TABLE = json.loads((Path(os.environ["RAYPC_SOURCE_DIR"]) / "src" / "grid" / "names.json").read_text())
COLUMNS = TABLE["columns"]
BRUSHES = {"version": 4, "brushes": [{"name": "temperature anomaly", "min": -1e9, "max": -25}]}


def header(path: Path) -> list:
    with open(path, newline="") as f:
        return next(csv.reader(f))


def with_units(name: str, units: str) -> str:
    return f"{name} [{units}]" if units else name


def test_the_module_holds_the_table_of_the_source_tree():
    # A module built from another table (a stale build) would name other columns than the CLI here.
    assert raypc.NAMES == TABLE


def test_derived_variables_have_the_tables_names_units_and_sources(contest):
    manifest = {v["name"]: v for v in json.loads((Path(contest.path) / "dataset.json").read_text())["variables"]}
    table = {v["name"]: v for v in TABLE["derivedVariables"]}
    derived = [v for v in contest.variables if v.derived]
    rule = TABLE["shellAnomaly"]
    # The contest's files have a velocity and an expansivity; their shell anomalies are computed when
    # read (not stored), the percentages only of variables whose shell means are positive.
    computed = [v for v in derived if manifest[v.name]["stored"] is False]
    assert {v.name for v in derived} - {v.name for v in computed} == {"radial velocity", "velocity magnitude"}
    assert "thermal expansivity anomaly" in {v.name for v in computed}
    for v in computed:
        source = manifest[v.name]["source"]
        assert manifest[source]["stored"] is True
        if manifest[v.name]["kind"] == "anomaly %":
            assert v.name.endswith(rule["percentSuffix"]) and v.units == rule["percentUnits"]
        else:
            assert v.name.endswith(rule["suffix"]) and v.units == manifest[source]["units"]
    for v in derived:
        if v in computed and v.name not in table:
            continue
        assert v.name in table, f"{v.name}: derived, but not in names.json"
        entry, source = table[v.name], manifest[v.name]["source"]
        if entry["units"] is None:  # an anomaly of the first of 'from' the model has, in its units
            assert source in entry["from"] and v.units == manifest[source]["units"]
        else:  # computed from all of 'from'
            assert source == ", ".join(entry["from"]) and v.units == entry["units"]


def test_stats_columns_are_the_tables(contest, tmp_path):
    raypc.State(BRUSHES).save(tmp_path / "s.json")
    run_cli("stats", contest.path, "--state", tmp_path / "s.json", "-o", tmp_path / "stats.csv", "--profile",
            tmp_path / "profile.csv", "--profile-var", "temperature anomaly", "--quiet")
    over_time = [c["name"] for c in COLUMNS["selectionOverTime"]]
    units = {v.name: v.units for v in contest.variables}["temperature anomaly"]
    profile = [c["name"] for c in COLUMNS["profile"]] + [
        p.format(name="temperature anomaly", units=units) for p in COLUMNS["profileMeans"]]
    assert profile[-2:] == ["temperature anomaly selected mean [K]", "temperature anomaly shell mean [K]"]
    assert header(tmp_path / "stats.csv") == over_time
    assert header(tmp_path / "profile.csv") == profile
    assert list(contest.stats(BRUSHES, progress=False).columns) == over_time
    assert list(contest.stats(BRUSHES, by="depth", mean_of="temperature anomaly", progress=False).columns) == profile


def test_pathline_columns_are_the_tables(contest, tmp_path):
    run_cli("export", contest.path, "--time", 0, "--what", "pathlines", "-o", tmp_path / "lines.csv")
    written = header(tmp_path / "lines.csv")
    points = COLUMNS["pathlinePoints"]
    # line, point, x, y, z, lat, lon, radius, time, age: the stored values x, y, z and time as named.
    assert [written[i] for i in (2, 3, 4, 8)] == [with_units(c["name"], c["units"]) for c in points]
    fixed = COLUMNS["pathlineAttributes"]
    per_variable = [(p + v.name, v.units) for p in COLUMNS["pathlineVariablePrefixes"] for v in contest.variables]
    assert written[10:] == [with_units(c["name"], c["units"]) for c in fixed] + [with_units(n, u) for n, u in per_variable]

    (stored,) = contest.pathlines(0, window=1)
    assert list(stored["points"].columns) == [c["column"] for c in points] + ["line"]
    lines = stored["lines"]
    assert list(lines.columns) == [c["name"] for c in fixed] + [n for n, _ in per_variable]
    assert [lines.attrs["units"][c["name"]] for c in fixed] == [c["units"] for c in fixed]
