"""A preset whose title speaks of a depth ("Cold slabs at 1600 km", examples/titles.tsv) shows the
reference shell at that depth (issue 47: the 1600 km presets showed none), so that the picture
says where the depth the title names lies. Usage: check_preset_shells.py EXAMPLES_DIR"""
import json
import re
import sys
from pathlib import Path

examples = Path(sys.argv[1])
checked, wrong = 0, []
for line in (examples / "titles.tsv").read_text().splitlines():
    if not line or line.startswith("#"):
        continue
    name, title = line.split("\t")
    depths = [float(d) for d in re.findall(r"at (\d+) km", title)]
    if not depths:
        continue
    shells = json.loads((examples / f"{name}.json").read_text()).get("reference", {}).get("shells", {})
    for depth in depths:
        checked += 1
        if not shells.get("visible") or depth not in shells.get("depthsKm", []):
            wrong.append(f"{name} ('{title}'): no visible shell at {depth:g} km (reference.shells: {shells})")
if wrong or checked < 4:
    sys.exit("\n".join(wrong) or f"only {checked} presets name a depth: expected the four task presets")
print(f"{checked} presets show the shell their title names")
