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
    """The netCDF/CF-safe name of a variable's display name, as the xarray Datasets name it:
    lower case, ``%`` spelled ``percent``, every run of other characters than letters, digits and
    ``_`` one ``_`` (``"temperature anomaly %"`` -> ``"temperature_anomaly_percent"``); a name that
    would not start with a letter gets ``v_`` in front (netCDF names must). The display name stays
    in the variable's ``long_name``."""
    import re

    name = display_name.lower().replace("%", " percent ")
    name = re.sub(r"[^a-z0-9_]+", "_", name).strip("_")
    if not name or not name[0].isalpha():
        name = "v_" + name
    return name


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
