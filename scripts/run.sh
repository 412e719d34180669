#!/usr/bin/env bash
# Sets up (packages, configure, build) and runs the main job on its embedded default.
# Extra arguments go to `hypershape`, e.g.  scripts/run.sh solve configs/scenes/ball.yaml -o ball.h5
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh >/dev/null
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OPENBLAS_NUM_THREADS=1
if [ $# -eq 0 ]; then
  mkdir -p results
  set -- solve -o results/default.h5
fi
exec build/hypershape "$@"
