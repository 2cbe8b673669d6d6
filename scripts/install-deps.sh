#!/usr/bin/env bash
# Installs what RayPC needs from Debian 12's packages, and only what is missing, so a second run
# is quick. Needs root (or sudo) for apt-get. Used by scripts/demo.sh and scripts/test.sh.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config time ccache
  libnetcdf-dev netcdf-bin          # input files; ncgen/nccopy write independent test files
  libpugixml-dev zlib1g-dev         # VTK XML input (ASPECT's .pvd/.pvtu/.vtu), not VTK itself
  libtbb-dev libhwy-dev libembree-dev
  libsharp-dev                      # spherical-harmonic transforms (raypc correlate --lmax, raypc spectrum)
  nlohmann-json3-dev libcli11-dev libspdlog-dev libfmt-dev
  libboost-dev libturbojpeg0-dev libpng-dev
  libopenmpi-dev openmpi-bin        # MPI: one binary, alone or under mpirun (docs/scaling.md)
  libfreetype-dev fonts-dejavu-core # legends in rendered pictures
  libgtest-dev libgmock-dev libbenchmark-dev
  pybind11-dev python3-dev python3-numpy # Python's raypc module (src/python, docs/python.md)
  python3-xarray python3-pandas     # its to_xarray and DataFrames
  python3-pip python3-setuptools python3-wheel # `pip install --no-build-isolation .` (pyproject.toml)
  python3-dask                      # xarray chunks={}: a lazy dask chunk per step and variable
  chromium                          # the web UI's browser tests
)
# Only the test command needs these: an independent XML parser and ParaView's Python, which
# check that ParaView opens the exported pathlines and critical points; Python's netCDF4, which
# writes the contest-layout fixture at test time (tests/data); pytest, Jupyter's nbclient and kernel,
# matplotlib, Pillow and a WebSocket client (a stand-in UI tab) for the Python module's tests and
# its example notebook (tests/python); clang with its sanitizer and libFuzzer runtimes and
# llvm-symbolizer for `scripts/test.sh --sanitize` and tests/fuzz/; GMT, which checks that it
# reads the maps and sections RayPC exports as netCDF grids (tests/cli, maps_sections); h5py, which
# writes the CitcomS HDF5 fixture at test time (tests/data/citcoms-layout); venv, in which the
# test of the pip-installed package installs its wheel (tests/python/test_wheel.py).
if [[ ${1:-} == --tests ]]; then
  packages+=(libxml2-utils python3-paraview python3-netcdf4 clang libclang-rt-14-dev llvm
             python3-pytest python3-nbclient python3-nbformat python3-ipykernel python3-matplotlib python3-pil
             python3-websocket gmt python3-h5py python3-venv)
fi
# Node.js and npm build the web UI; a machine may carry them from elsewhere (npm bundled with
# nodejs), so ask for Debian's only when the commands are missing.
command -v node >/dev/null || packages+=(nodejs)
command -v npm >/dev/null || packages+=(npm)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if ((${#missing[@]})); then
  echo "install-deps: installing ${missing[*]}" >&2
  sudo_cmd=()
  if [[ $(id -u) -ne 0 ]]; then sudo_cmd=(sudo); fi
  export DEBIAN_FRONTEND=noninteractive
  "${sudo_cmd[@]}" apt-get update -qq
  "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
