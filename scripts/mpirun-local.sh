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
args=(--oversubscribe)
if [[ $(id -u) -eq 0 ]]; then args+=(--allow-run-as-root); fi
exec mpirun "${args[@]}" "$@"
