"""The names of the variables raypc derives and of the columns of the tables it writes
(src/grid/names.json, from which the C++ code's names are generated too), as the compiled module
holds them: the columns this package builds are named from it, so that they are the CLI's."""
from __future__ import annotations

import json

from . import _raypc

NAMES: dict = json.loads(_raypc.names_json())
_COLUMNS = NAMES["columns"]
_PATHLINE_ATTRIBUTE = {c["key"]: c["name"] for c in _COLUMNS["pathlineAttributes"]}
