"""The example notebook (examples/task1-slabs-660km.ipynb) executed headless by nbclient on a
small synthetic series given as netCDF files (raypc synth), so that it cannot rot: every cell runs
without error, the figure and the plots are there (the map through xarray's engine "raypc"), and its
tables equal the module's statistics and stalls."""
import os
from pathlib import Path

import nbclient
import nbformat

import raypc
from conftest import run_cli

EXAMPLES = Path(os.environ["RAYPC_SOURCE_DIR"]) / "examples"


def test_task1_notebook_runs(tmp_path, monkeypatch):
    run_cli("synth", "-o", tmp_path / "nc", "--steps", 4, "--grid", "32x41x64")
    monkeypatch.setenv("RAYPC_DATASET", str(tmp_path / "nc"))
    nb = nbformat.read(EXAMPLES / "task1-slabs-660km.ipynb", as_version=4)
    nbclient.NotebookClient(nb, timeout=600, kernel_name="python3",
                            resources={"metadata": {"path": str(EXAMPLES)}}).execute()
    outputs = [o for cell in nb.cells if cell.cell_type == "code" for o in cell.outputs]
    assert not [o for o in outputs if o.output_type == "error"]
    images = [o for o in outputs if "image/png" in o.get("data", {})]
    assert len(images) >= 4  # the rendered picture, the time series, the depth profile, the map
    html = [o["data"]["text/html"] for o in outputs if "text/html" in o.get("data", {})]
    assert any("<iframe" in h for h in html)  # the linked view
    # the notebook's table is the module's statistics of the preset on that dataset
    ds = raypc.open(tmp_path / "nc", progress=False)
    state = raypc.State(EXAMPLES / "task1-slabs-660km.json")
    expected = ds.stats(state, progress=False)
    assert expected["selected_volume_km3"].gt(0).any()
    texts = [o["data"]["text/plain"] for o in outputs if "text/plain" in o.get("data", {})]
    assert repr(expected) in texts
    # its stall table is the module's tracks of the cold sinking material (raypc features --stalls)
    slabs = raypc.State(state.to_dict())
    slabs.brushes = [b for b in slabs.brushes if b["name"] != "depth"]
    stalls = ds.tracks(slabs, stall_by="deepest", depths_km=[660], progress=False).stalls
    shown = stalls.sort_values("duration_myr", ascending=False, ignore_index=True)
    assert repr(shown[["track", "depth_km", "duration_myr", "first_step", "last_step", "left"]]) in texts
    # the dataset was preprocessed beside the files, where the next open found it
    assert ds.path == tmp_path / "nc" / "spherical.raypc"
