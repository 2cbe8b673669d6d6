#!/usr/bin/env bash
# The second README command: install what is missing, build, and run every test.
#
#   scripts/test.sh              Release build in build/, every test (ctest)
#   scripts/test.sh --sanitize   clang build in build-sanitize/ with AddressSanitizer and
#                                UndefinedBehaviorSanitizer (float-cast-overflow included, every
#                                report fatal), every test but the browser ones; the libFuzzer
#                                targets are built there too (tests/fuzz/run.sh runs them)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/install-deps.sh" --tests
if [[ ${1:-} != --sanitize ]]; then
  "$root/scripts/build.sh"
  cd "${RAYPC_BUILD_DIR:-$root/build}"
  ctest --output-on-failure -j "$(nproc)" --timeout 600
  exit
fi

build=${RAYPC_SANITIZE_BUILD_DIR:-$root/build-sanitize}
# No NDEBUG (a build type of its own): debug checks stay on. -O1 keeps the tests fast enough;
# -fsanitize=fuzzer-no-link adds libFuzzer's coverage to the libraries the fuzz targets link.
sanitizers="-fsanitize=address,undefined,float-cast-overflow -fno-sanitize-recover=all"
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
if [[ ! -f $build/build.ninja ]]; then
  cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Sanitize \
    -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ "${launcher[@]}" \
    -DCMAKE_C_FLAGS="-O1 -g1 -fno-omit-frame-pointer $sanitizers" \
    -DCMAKE_CXX_FLAGS="-O1 -g1 -fno-omit-frame-pointer $sanitizers -fsanitize=fuzzer-no-link" \
    -DCMAKE_EXE_LINKER_FLAGS="$sanitizers" -DRAYPC_BUILD_BENCH=OFF -DRAYPC_FUZZ=ON >/dev/null
fi
cmake --build "$build" -j "$(nproc)"
cd "$build"
# Browser tests drive Chromium against a server; they are left to the Release run.
ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:strict_string_checks=1} \
UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1} \
  ctest --output-on-failure -j "$(nproc)" --timeout 1200 -E '^browser\.'
