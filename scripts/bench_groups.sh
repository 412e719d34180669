#!/usr/bin/env bash
# Group-scaling benchmark (issue 16): one large 3D shape — the unit ball, P2, mesh size H
# (default 0.115: ~110k unknowns), the 3D presets' patch and load (r 0.4, gamma 0.1), one load
# case to max|u| = TARGET — solved by `hypershape solve` on 1 and on 2 ranks (one solver group),
# with each linear solver of SOLVERS (default: direct gamg), REPEATS times (default 3), the
# rank counts interleaved (1, 2, 1, 2, ...) so that a load on the shared machine hits both alike.
# Prints a table of medians and writes every run (JSON, with -log_view's event counts and the
# communication it measured) to OUT (default results/bench_groups.json), and a strong-scaling
# projection to 8-64 ranks from the measured communication volume and the partition's cut
# (scripts/bench_groups_table.py says how).
#   scripts/bench_groups.sh [H] [REPEATS]
#   SOLVERS="direct gamg hypre" RANKS="1 2" TARGET=0.3 scripts/bench_groups.sh 0.15 3
set -euo pipefail
cd "$(dirname "$0")/.."
h=${1:-0.115} repeats=${2:-3}
solvers=${SOLVERS:-direct gamg} ranks=${RANKS:-1 2} target=${TARGET:-0.3}
out=${OUT:-results/bench_groups.json} bin=${BIN:-build/hypershape}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for s in $solvers; do
  cat > "$work/ball_$s.yaml" <<YAML
# The 3D presets' set-up on the unit ball (patch r 0.4, gamma 0.1, E 500, nu 0.49), P2 at h $h.
geometry: {base: sphere}
mesh: {h: $h, degree: 2}
effects:
  neo_hookean: {E: 500, nu: 0.49}
  dirichlet_patch: {center: [1.0, 0.0, 0.0], radius: 0.4}
  gaussian_traction: {center: [-1.0, 0.0, 0.0], direction: [0.0, 1.0, 0.0], gamma: 0.1}
load: {target: $target}
solver: {linear: $s}
YAML
done
for ((k = 0; k < repeats; ++k)); do
  for s in $solvers; do
    for n in $ranks; do
      tag="$s-np$n-$k"
      /usr/bin/time -f "%e %U %S %M" -o "$work/$tag.time" \
        mpiexec -n "$n" "$bin" solve "$work/ball_$s.yaml" -o "$work/$tag.h5" -log_view ":$work/$tag.log" \
        > "$work/$tag.out" 2>&1 || { cat "$work/$tag.out" >&2; exit 1; }
      echo "[bench_groups] $tag: $(grep -o 'converged.*' "$work/$tag.out" | head -c 160)" >&2
    done
  done
done
mkdir -p "$(dirname "$out")"
/usr/bin/python3 scripts/bench_groups_table.py "$work" "$out" --h "$h" --target "$target" --repeats "$repeats" \
  --solvers $solvers --ranks $ranks
