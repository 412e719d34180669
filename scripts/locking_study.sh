#!/usr/bin/env bash
# Volumetric locking of P2 at nu 0.49 / 0.499 (README, "Nearly incompressible bodies without
# locking"): max|u| at a fixed alpha under uniform refinement, the seed's pointwise Neo-Hookean
# against `dilatation: mean`, on the disk (configs/scenes/disk_p2.yaml, nu 0.49 and 0.499) and
# the ball (configs/scenes/ball.yaml). Prints one line per solve: scene, nu, element, h, unknowns,
# max|u|, solve seconds. The finest solves take minutes (ball h 0.1: 102k unknowns).
#   scripts/locking_study.sh [build/hypershape]
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${1:-build/hypershape}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
solve() {  # $1 scene, $2 nu, $3 dilatation, $4 h, $5 alpha, $6 the scene's own h
  sed "s/nu: 0.49}/nu: $2, dilatation: $3}/; s/h: $6/h: $4/; s/load: {target: 0.3}/load: {alpha: $5}/" \
    "configs/scenes/$1.yaml" > "$work/s.yaml"
  local line
  line=$("$bin" solve "$work/s.yaml" -o "$work/s.h5" 2>&1 | tail -1)
  echo "$1 nu $2 $3 h $4: $(grep -o '[0-9]* dofs' <<< "$line"), $(grep -o 'max|u| [0-9.]*' <<< "$line"), $(grep -o 'solve [0-9.]*s' <<< "$line")"
}
# alpha: the load at max|u| = 0.3 with the pointwise element at the scene's own h.
for nu_alpha in "0.49 8.99024" "0.499 9.11155"; do
  set -- $nu_alpha
  for dil in pointwise mean; do
    for h in 0.2 0.1 0.05 0.025; do
      [ $dil = mean ] && [ $h = 0.025 ] && continue
      solve disk_p2 "$1" $dil $h "$2" 0.05
    done
  done
done
for dil in pointwise mean; do
  for h in 0.4 0.25 0.15 0.1; do solve ball 0.49 $dil $h 7.2058 0.25; done
done
