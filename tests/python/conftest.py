"""Fixtures of the Python module's tests (run by ctest as python.*, see CMakeLists.txt).

RAYPC_EXE: the raypc executable; RAYPC_TEST_DATA_DIR: the test_data fixture (contest-layout/ written
by Python's netCDF4 with its truth.json); the module is imported from the build tree (PYTHONPATH).
"""
import json
import os
import subprocess
from pathlib import Path

import pytest

import raypc

RAYPC_EXE = os.environ["RAYPC_EXE"]
CONTEST_LAYOUT = Path(os.environ["RAYPC_TEST_DATA_DIR"]) / "contest-layout"


def run_cli(*args, check=True):
    """Runs the raypc executable; returns the completed process (text)."""
    result = subprocess.run([RAYPC_EXE, *map(str, args)], capture_output=True, text=True, timeout=600)
    if check and result.returncode != 0:
        raise AssertionError(f"raypc {' '.join(map(str, args))} failed: {result.stderr}")
    return result


@pytest.fixture(scope="session")
def truth():
    return json.loads((CONTEST_LAYOUT / "truth.json").read_text())


@pytest.fixture(scope="session")
def contest(tmp_path_factory):
    """The three contest-layout files opened (preprocessed) by raypc.open, exact float32 levels."""
    out = tmp_path_factory.mktemp("contest") / "contest.raypc"
    files = sorted(CONTEST_LAYOUT.glob("spherical*.nc"))
    assert len(files) == 3
    return raypc.open(*files, dataset=out, encoding="float32", sample_rows=2000, progress=False)
