#!/usr/bin/env bash
# Correlation and spectra on the sphere (docs/compare.md): bench/compare_sphere_bench.cpp on two 1°
# global fields (181 x 360 x 50 shells), with the machine's load before and after (the cores may be
# shared). Targets (issue 45): the correlation per depth <= 1 s on 2 cores, a spectrum to degree 60 of
# 50 shells <= 2 s.
#   bench/compare_sphere.sh [BUILD_DIR]   (default: build)
set -euo pipefail
build=${1:-build}
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ //')"
echo "load before: $(uptime)"
"$build/bench/compare_sphere_bench" --benchmark_min_time=1
echo "load after: $(uptime)"
