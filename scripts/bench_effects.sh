#!/usr/bin/env bash
# What each effect costs per load case, and the paper's preset against a previous build: a
# Random2D slice (default 4 shapes x 10 load cases, the preset's h and 128^2 grids), 1 rank,
# run REPEATS times (default 2) alternately as
#   paper          the preset (neo_hookean, dirichlet_patch, gaussian_traction: its shorthands)
#   previous       the same with PREVIOUS_BIN (a build from before datasets chose their effects),
#                  when given: same speed within noise is the claim
#   gravity        + body_force {value: [0, -2], scale: fixed} (a second load vector)
#   tractions3     gaussian_traction as a list of three
#   E_shape        E drawn uniform [400, 600] per shape
#   spring         + spring {stiffness: 10} on the whole free boundary
#   inclusions     Neo-Hookean with 3 inclusions (radius 0.25, 5x stiffer; a modulus channel)
#   grf            Neo-Hookean with a log-normal GRF modulus (cv 0.3, correlation length 0.3)
#   supports3      + two fixed dirichlet regions (clamps2d's: x <= -0.85; a ball of radius 0.5 at (0, -1.4))
#   pressure       + a fixed dead pressure 2 on the whole boundary
#   mooney_rivlin  Mooney-Rivlin (C1 60, C2 24, kappa 8333: mu, K of E 500, nu 0.49) instead
#   linear_elastic linear elasticity instead (one linear solve per load case: alpha exact)
#   follower       + a fixed follower pressure 2 on the whole boundary (LU solves)
#   p2, p2_mean    P2 on the same mesh, the pointwise Neo-Hookean and dilatation: mean (compare
#                  p2_mean with p2, not with paper)
#   organ_pressure (3D presets only) + configs/examples/organ_pressure3d.yaml's pressure, fixed at
#                  its middle value 0.65 on the facets at z >= 0.2
# PRESET=aug_liver (or random3d, liver, one_liver) runs a 3D slice of that preset instead: its
# patch radius 0.4 and gamma 0.1, targets [0.2, 0.5] (organ_pressure3d's) for every variant;
# VARIANTS="paper spring" runs only those ("paper", the base of the ratios, always; in 3D the
# default is "paper organ_pressure": gravity and the regions of the others are 2D values):
#   PRESET=aug_liver VARIANTS="paper organ_pressure" scripts/bench_effects.sh 2 10 2
# Prints JSON and a markdown table: the median seconds per load case (setup + solve + alpha
# search + representations + gather, summed over the load cases) and its ratio to "paper"
# measured in the same run (on a loaded host trust the ratio and the Newton iterations per
# load case more than the seconds), and the converged share. The supports3 variant redraws a
# shape that misses a region, so its shapes may differ from the others'. JSON:
# results/bench_effects.json.
#   scripts/bench_effects.sh [SHAPES] [LOADS] [REPEATS] [PREVIOUS_BIN]
set -euo pipefail
cd "$(dirname "$0")/.."
shapes=${1:-4} loads=${2:-10} repeats=${3:-2} previous=${4:-}
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
preset=${PRESET:-random2d}
case $preset in random3d | aug_liver | liver | one_liver) dim=3 ;; *) dim=2 ;; esac
if [ $dim = 3 ]; then : "${VARIANTS:=paper organ_pressure}"; fi  # the others' values are 2D ones
head="preset: $preset
name: bench_effects
shapes: {count: $shapes}
loads: {count: $loads$(if [ $dim = 3 ]; then echo ", target: [0.2, 0.5]"; fi)}
output: {shard_size: 2}"
nh="  neo_hookean: {E: 500, nu: 0.49}"
patch="  dirichlet_patch: {radius: $([ $dim = 3 ] && echo 0.4 || echo 0.5)}"
traction="  gaussian_traction: {gamma: $([ $dim = 3 ] && echo 0.1 || echo 0.2)}"
# variant name, then its effects (one line each; "" for the preset's shorthands).
variant() {
  local name=$1
  shift
  [[ $name == paper || -z ${VARIANTS:-} || " $VARIANTS " == *" $name "* ]] || return 0
  if [ $# -eq 0 ]; then printf '%s\n' "$head" > "$work/$name.yaml"
  else { printf '%s\neffects:\n' "$head"; printf '%s\n' "$@"; } > "$work/$name.yaml"; fi
  variants+=" $name"
}
variants=""
variant paper
variant gravity "$nh" "$patch" "$traction" "  body_force: {value: [0, -2], scale: fixed}"
variant tractions3 "$nh" "$patch" "  gaussian_traction: [{gamma: 0.2}, {gamma: 0.2}, {gamma: 0.2}]"
variant E_shape "  neo_hookean: {E: {uniform: [400, 600]}, nu: 0.49}" "$patch" "$traction"
variant spring "$nh" "$patch" "$traction" "  spring: {stiffness: 10}"
variant inclusions "  neo_hookean: {E: 500, nu: 0.49, inclusions: 3, inclusion_radius: 0.25, inclusion_ratio: 5}" \
  "$patch" "$traction"
variant grf "  neo_hookean: {E: 500, nu: 0.49, E_cv: 0.3, E_length: 0.3}" "$patch" "$traction"
variant supports3 "$nh" "$patch" "  dirichlet: [{box: [-3, -3, -0.85, 3]}, {center: [0, -1.4], radius: 0.5}]" "$traction"
variant pressure "$nh" "$patch" "$traction" "  pressure: {value: 2, scale: fixed}"
variant mooney_rivlin "  mooney_rivlin: {C1: 60, C2: 24, kappa: 8333}" "$patch" "$traction"
variant linear_elastic "  linear_elastic: {E: 500, nu: 0.49}" "$patch" "$traction"
variant follower "$nh" "$patch" "$traction" "  pressure: {value: 2, follower: true, scale: fixed}"
variant p2 "$nh" "$patch" "$traction" "mesh: {degree: 2}"
variant p2_mean "  neo_hookean: {E: 500, nu: 0.49, dilatation: mean}" "$patch" "$traction" "mesh: {degree: 2}"
if [ $dim = 3 ]; then
  variant organ_pressure "$nh" "$patch" "$traction" "  pressure: {value: 0.65, box: [-3, -3, 0.2, 3, 3, 3], scale: fixed}"
fi
for ((k = 0; k < repeats; ++k)); do
  for v in $variants; do build/hypershape -q generate "$work/$v.yaml" --progress 0 -o "$work/$v-$k"; done
  if [ -n "$previous" ]; then "$previous" -q generate "$work/paper.yaml" --progress 0 -o "$work/previous-$k"; fi
  echo "run $((k + 1))/$repeats done" >&2
done
mkdir -p results
/usr/bin/python3 - "$work" "$repeats" "${previous:+previous}" $variants <<'PY'
import json, statistics, sys
work, repeats, names = sys.argv[1], int(sys.argv[2]), [n for n in sys.argv[3:] if n]
label = {"paper": "the preset (neo_hookean, dirichlet_patch, gaussian_traction)", "previous": "the preset, previous build",
         "gravity": "+ fixed gravity (body_force, scale: fixed)", "tractions3": "3 tractions (a list)",
         "E_shape": "E drawn per shape", "spring": "+ spring bed on the free boundary (k = 10)",
         "inclusions": "3 inclusions (r 0.25, 5x stiffer)", "grf": "log-normal GRF modulus (cv 0.3, length 0.3)",
         "supports3": "+ 2 fixed dirichlet regions (3 supports)", "pressure": "+ fixed dead pressure 2 (whole boundary)",
         "mooney_rivlin": "Mooney-Rivlin instead (C1 60, C2 24, kappa 8333: the same mu, K)",
         "linear_elastic": "linear elasticity instead (one linear solve)",
         "organ_pressure": "+ fixed dead pressure 0.65 on the upper side (z >= 0.2; organ_pressure3d's)",
         "follower": "+ fixed follower pressure 2 (whole boundary; LU solves)",
         "p2": "P2 on the same mesh (pointwise Neo-Hookean)",
         "p2_mean": "P2, neo_hookean dilatation: mean (compare with P2)"}
rows = {}
for n in names:
    per_load, newton, conv = [], [], []
    for k in range(repeats):
        r = json.load(open(f"{work}/{n}-{k}/reports/task-000-of-001.json"))
        p = r["seconds"]["phases_summed_over_groups"]
        lc = r["load_cases"]["converged"] + r["load_cases"]["failed"]
        per_load.append(sum(p.get(x, 0.0) for x in ("setup", "solve", "alpha_search", "representations", "gather")) / lc)
        newton.append(r["solver"]["newton_iterations"] / lc)
        conv.append(r["load_cases"]["converged"] / lc)
    rows[n] = {"label": label[n], "seconds_per_load_case": statistics.median(per_load), "runs": per_load,
               "newton_per_load_case": statistics.median(newton), "converged_share": min(conv)}
base = rows["paper"]["seconds_per_load_case"]
for r in rows.values():
    r["relative_cost"] = r["seconds_per_load_case"] / base
print(json.dumps(rows, indent=1))
print("\n| variant | s / load case | relative to the preset | Newton it. / load case | converged |")
print("|---|---|---|---|---|")
for n, r in rows.items():
    print(f"| {r['label']} | {r['seconds_per_load_case']:.4f} | {r['relative_cost']:.2f} | "
          f"{r['newton_per_load_case']:.1f} | {100 * r['converged_share']:.0f}% |")
json.dump(rows, open("results/bench_effects.json", "w"), indent=1)
PY
