#!/usr/bin/env bash
# Builds the browser UI into web/dist. Installs the exact npm dependencies (npm ci) only when
# web/node_modules is missing or package-lock.json is newer than the last install, and bundles
# only when a source is newer than the bundle, so a second run is quiet and quick.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
web=$root/web
cd "$web"
stamp=node_modules/.raypc-installed
if [[ ! -f $stamp || package-lock.json -nt $stamp || package.json -nt $stamp ]]; then
  echo "build-web: npm ci" >&2
  npm ci --no-audit --no-fund --loglevel=error >/dev/null
  touch "$stamp"
fi
# The tables the UI imports from ../src (names.json, display_units.json, the colour maps) count as sources.
if [[ ! -f dist/app.js || ! -f dist/sample_worker.js || ! -f dist-test/app.js ||
      -n $(find src build.mjs package-lock.json -newer dist/app.js -print -quit) ||
      -n $(find ../src -name '*.json' -newer dist/app.js -print -quit) ]]; then
  node build.mjs
fi
