#!/usr/bin/env bash
# Sets up (packages, configure, build) and runs the main job on its embedded default: a small
# Random2D dataset (4 shapes x 6 load cases) -> results/default/ (a rerun finds it complete).
#   NP=2 scripts/run.sh                                   the same on 2 MPI ranks
#   scripts/run.sh generate configs/presets/random2d.yaml  any hypershape command
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh hypershape_cli >/dev/null  # the CLI only (scripts/test.sh builds the rest)
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1
[ $# -eq 0 ] && set -- generate -o results/default
np=${NP:-1}
if [ "$np" -gt 1 ]; then exec mpiexec -n "$np" build/hypershape "$@"; fi
exec build/hypershape "$@"
