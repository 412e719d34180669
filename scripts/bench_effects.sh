#!/usr/bin/env bash
# What each effect costs per load case, and the paper's preset against a previous build: a
# Random2D slice (default 4 shapes x 10 load cases, the preset's h and 128^2 grids), 1 rank,
# run REPEATS times (default 2) alternately as
#   paper          the preset (neo_hookean, dirichlet_patch, gaussian_traction: its shorthands)
#   previous       the same with PREVIOUS_BIN (a build from before datasets chose their effects),
#                  when given: same speed within noise is the claim
#   +gravity       + body_force {value: [0, -2], scale: fixed} (a second load vector)
#   3 tractions    gaussian_traction as a list of three
#   E per shape    E drawn uniform [400, 600] per shape
# Prints the median seconds per load case (setup + solve + alpha search + representations +
# gather, summed over the load cases, over the converged ones) and Newton iterations per load
# case; the difference to "paper" is the effect's marginal cost (its loads also change the
# solves, hence the iterations column). JSON: results/bench_effects.json.
#   scripts/bench_effects.sh [SHAPES] [LOADS] [REPEATS] [PREVIOUS_BIN]
set -euo pipefail
cd "$(dirname "$0")/.."
shapes=${1:-4} loads=${2:-10} repeats=${3:-2} previous=${4:-}
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
head="preset: random2d
name: bench_effects
shapes: {count: $shapes}
loads: {count: $loads}
output: {shard_size: 2}"
paper_effects="  neo_hookean: {E: 500, nu: 0.49}
  dirichlet_patch: {radius: 0.5}"
printf '%s\n' "$head" > "$work/paper.yaml"
printf '%s\neffects:\n%s\n  gaussian_traction: {gamma: 0.2}\n  body_force: {value: [0, -2], scale: fixed}\n' \
  "$head" "$paper_effects" > "$work/gravity.yaml"
printf '%s\neffects:\n%s\n  gaussian_traction: [{gamma: 0.2}, {gamma: 0.2}, {gamma: 0.2}]\n' \
  "$head" "$paper_effects" > "$work/tractions3.yaml"
printf '%s\neffects:\n  neo_hookean: {E: {uniform: [400, 600]}, nu: 0.49}\n  dirichlet_patch: {radius: 0.5}\n  gaussian_traction: {gamma: 0.2}\n' \
  "$head" > "$work/E_shape.yaml"
variants="paper gravity tractions3 E_shape"
for ((k = 0; k < repeats; ++k)); do
  for v in $variants; do build/hypershape -q generate "$work/$v.yaml" --progress 0 -o "$work/$v-$k"; done
  if [ -n "$previous" ]; then "$previous" -q generate "$work/paper.yaml" --progress 0 -o "$work/previous-$k"; fi
  echo "run $((k + 1))/$repeats done" >&2
done
mkdir -p results
/usr/bin/python3 - "$work" "$repeats" "${previous:+previous}" $variants <<'PY'
import json, statistics, sys
work, repeats, names = sys.argv[1], int(sys.argv[2]), [n for n in sys.argv[3:] if n]
label = {"paper": "paper (preset)", "previous": "paper, previous build", "gravity": "+ fixed gravity",
         "tractions3": "3 tractions", "E_shape": "E drawn per shape"}
rows = {}
for n in names:
    per_load, newton = [], []
    for k in range(repeats):
        r = json.load(open(f"{work}/{n}-{k}/reports/task-000-of-001.json"))
        p = r["seconds"]["phases_summed_over_groups"]
        lc = r["load_cases"]["converged"] + r["load_cases"]["failed"]
        per_load.append(sum(p.get(x, 0.0) for x in ("setup", "solve", "alpha_search", "representations", "gather")) / lc)
        newton.append(r["solver"]["newton_iterations"] / lc)
    rows[n] = {"seconds_per_load_case": statistics.median(per_load), "runs": per_load,
               "newton_per_load_case": statistics.median(newton)}
base = rows["paper"]["seconds_per_load_case"]
print(f"{'variant':24s} {'s/load case':>12s} {'vs paper':>9s} {'Newton/load':>12s}")
for n, r in rows.items():
    s = r["seconds_per_load_case"]
    print(f"{label[n]:24s} {s:12.4f} {s - base:+9.4f} {r['newton_per_load_case']:12.1f}")
json.dump(rows, open("results/bench_effects.json", "w"), indent=1)
PY
