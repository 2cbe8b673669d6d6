# What the benchmark scripts of bench/ share. Each sources it after `set -euo pipefail`:
#   . "$(dirname "$0")/common.sh"          (from bench/peers or bench/soak: "$(dirname "$0")/../common.sh")
# It sets `root` (the repository) and defines the functions below.
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)

# The machine, which a benchmark prints with its figures: "N cores, CPU model".
machine() {
  echo "$(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')"
}

# bench_dirs NAME [BUILD_DIR] [WORK_DIR]: the two arguments most scripts take. Sets `build`
# (default build/), `raypc` ($build/raypc; exits when it is not built) and `work` (default
# ${TMPDIR:-/tmp}/raypc-bench-NAME, created).
bench_dirs() {
  build=${2:-$root/build}
  work=${3:-${TMPDIR:-/tmp}/raypc-bench-$1}
  raypc=$build/raypc
  [[ -x $raypc ]] || { echo "no $raypc: build first (scripts/build.sh)" >&2; exit 1; }
  mkdir -p "$work"
}
