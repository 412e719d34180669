#!/usr/bin/env bash
# Sets up (packages, configure, build) and runs the whole test suite with CTest.
# Slow tests carry the CTest label "slow" and run only with: scripts/test.sh -C slow -L slow
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
jobs=$(getconf _NPROCESSORS_ONLN)  # before OMP_NUM_THREADS=1: GNU nproc would report 1
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1
args=("$@")
[ ${#args[@]} -eq 0 ] && args=(-LE slow)
cd "${BUILD_DIR:-build}"
ctest --no-tests=error --output-on-failure --parallel "$jobs" "${args[@]}"
