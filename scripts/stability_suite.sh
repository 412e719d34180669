#!/usr/bin/env bash
# Issue 5's stability suite: the hard cases of tests/stability/ (near-incompressibility, large
# displacements, concentrated loads, thin necks, tiny clamps, flat bodies, adversarial solver
# settings), CI-sized and slow variants together. Sets up and builds like scripts/test.sh, then
# runs `unit_tests "[stability]"`; each case prints its table (converged, alpha, Newton
# iterations, failed increments, seconds). Exits non-zero if any case fails.
#   scripts/stability_suite.sh               # everything tagged [stability]
#   scripts/stability_suite.sh "~[slow]"     # extra Catch arguments, e.g. only the CI size
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1
exec "${BUILD_DIR:-build}/tests/unit_tests" "[stability]$*" --durations yes
