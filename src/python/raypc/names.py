"""The names of the variables raypc derives and of the columns of the tables it writes
(src/grid/names.json, from which the C++ code's names are generated too), as the compiled module
holds them: the columns this package builds are named from it, so that they are the CLI's."""
from __future__ import annotations

import json

from . import _raypc

NAMES: dict = json.loads(_raypc.names_json())
_COLUMNS = NAMES["columns"]
_PATHLINE_ATTRIBUTE = {c["key"]: c["name"] for c in _COLUMNS["pathlineAttributes"]}


def cf_name(display_name: str) -> str:
    """The netCDF/CF-safe name of a variable's display name, as the xarray Datasets and every file
    raypc writes name it (one rule, io::cfName in the compiled module): ``%`` spelled ``percent``,
    every run of other characters than letters, digits and ``_`` one ``_``, none at either end, and
    ``v_`` in front of a name that would not start with a letter (netCDF names must); case kept
    (``"temperature anomaly %"`` -> ``"temperature_anomaly_percent"``, ``"dlnVs"`` stays). The
    display name stays in the variable's ``long_name``."""
    if not isinstance(display_name, str):
        raise TypeError(f"display_name: expected a str, not {type(display_name).__name__}")
    return _raypc.cf_name(display_name)


def cf_names(display_names) -> dict:
    """``{display name: CF name}`` for a dataset's variables, unique: a name that two display names
    map to (``"a b"`` and ``"a_b"``) gets ``_2``, ``_3`` … after the first, in dataset order."""
    out, taken = {}, set()
    for display in display_names:
        base = name = cf_name(display)
        k = 2
        while name in taken:
            name, k = f"{base}_{k}", k + 1
        taken.add(name)
        out[display] = name
    return out
