#!/usr/bin/env bash
# Runs a command under Open MPI's mpirun on this one machine, the way the tests, bench/ and docs do:
#   scripts/mpirun-local.sh -np 2 build/raypc stats DATASET -o stats.csv
# Shared memory only (btl self,vader: no network, works in a container without one), more ranks
# than cores allowed (--oversubscribe), and as root where containers run (--allow-run-as-root).
# On a cluster use the site's mpirun or srun directly (docs/scaling.md).
set -euo pipefail
export OMPI_MCA_btl=${OMPI_MCA_btl:-self,vader}
# Everything is local: never look for ssh to start daemons.
export OMPI_MCA_plm_rsh_agent=${OMPI_MCA_plm_rsh_agent:-false}
# Under the sanitizers (scripts/test.sh --sanitize; no effect on other builds): Open MPI keeps its
# components loaded and leak stacks are unwound in full, so that tests/sanitize/lsan.supp can
# recognise the allocations Open MPI keeps until exit by the libraries on their stacks.
export OMPI_MCA_mca_base_component_disable_dlclose=${OMPI_MCA_mca_base_component_disable_dlclose:-1}
export ASAN_OPTIONS=${ASAN_OPTIONS:+$ASAN_OPTIONS:}fast_unwind_on_malloc=0
args=(--oversubscribe)
if [[ $(id -u) -eq 0 ]]; then args+=(--allow-run-as-root); fi
exec mpirun "${args[@]}" "$@"
