#!/usr/bin/env bash
# raypc demo, as README's first command runs it but on a free port: it makes the demo data, writes
# demo.png, then serves the UI with the same presets as `raypc serve` (GET /api/presets not empty).
# Usage: demo_serve_test.sh RAYPC
set -euo pipefail
raypc=$1
work=$(mktemp -d)
pid=
cleanup() { [[ -n $pid ]] && kill "$pid" 2>/dev/null; wait 2>/dev/null; rm -rf "$work"; }
trap cleanup EXIT

# The files exist before the loop reads them: the background job opens them when it is scheduled,
# which under a loaded test run can be after the first read.
: >"$work/out.txt"; : >"$work/err.txt"
"$raypc" demo --dir "$work/demo" --port 0 >>"$work/out.txt" 2>>"$work/err.txt" </dev/null &
pid=$!
url=
for _ in $(seq 1 1200); do  # the data and the picture take about a minute on 2 cores
  url=$(sed -n 's/^raypc: serving \(http[^ ]*\)$/\1/p' "$work/out.txt")
  [[ -n $url ]] && break
  kill -0 "$pid" 2>/dev/null || { echo "raypc demo exited before serving:"; cat "$work/err.txt"; exit 1; }
  sleep 0.5
done
[[ -n $url ]] || { echo "raypc demo did not print 'raypc: serving URL' within 600 s"; exit 1; }

head -c 8 "$work/demo/demo.png" | od -An -tx1 | grep -q '89 50 4e 47' || { echo "demo.png is not a PNG"; exit 1; }

python3 - "$url" <<'PY'
import json, sys, urllib.request
url = sys.argv[1]
presets = json.load(urllib.request.urlopen(url + "api/presets", timeout=30))
names = [p["name"] for p in presets]
print("presets:", names)
assert len(presets) > 0, "the demo serves no presets"
for p in presets:
    assert isinstance(p.get("state"), dict) and p.get("title"), f"preset without state or title: {p}"
page = urllib.request.urlopen(url, timeout=30).read().decode()
assert "<html" in page.lower(), "the demo's page is not HTML"
PY
