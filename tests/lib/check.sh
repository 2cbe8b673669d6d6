# Sourced by the command-line test scripts (tests/cli, tests/pathlines_cli, tests/mpi).
# make_work NAME: a temporary directory in $work, removed when the script exits.
make_work() {
  work=$(mktemp -d "${TMPDIR:-/tmp}/raypc-$1.XXXXXX")
  trap 'rm -rf "$work"' EXIT
}

# check DESCRIPTION COMMAND...: runs COMMAND, prints ok/FAIL and counts the failures.
failures=0
check() {
  local what=$1; shift
  if "$@"; then echo "ok: $what"; else echo "FAIL: $what"; failures=$((failures + 1)); fi
}
