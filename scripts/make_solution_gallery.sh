#!/usr/bin/env bash
# Solution galleries of the dataset presets -> docs/figures/<preset>_solutions.png.
#
#   scripts/make_solution_gallery.sh                       # every preset
#   PRESETS="random2d random3d" scripts/make_solution_gallery.sh
#
# For each preset: `hypershape generate --preset NAME --mini` (a few shapes and load cases, see
# the README's "Mini datasets") into $DATA_DIR/NAME, then
# `scripts/hypershape_data.py plot DIR --gallery 4`: the first 4 converged load cases (load 0 of
# each shape first), each panel the deformed shape coloured by |u| with the Dirichlet patch and
# the traction. Prints each preset's generate and plot times and the total. A preset whose
# surface file is missing (aug_liver's configs/surfaces/organ.stl, made by
# scripts/make_organ_surface.py) is skipped with a note.
#
# Environment:
#   HYPERSHAPE_BIN  the CLI (default build/hypershape)
#   PRESETS         preset names (default: all nine; PRESETS= for none)
#   CONFIGS         example dataset configs drawn as they are (default: configs/examples/*.yaml;
#                   CONFIGS= for none)
#   DATA_DIR        where the mini datasets go (default results/gallery; rewritten)
#   OUT_DIR         figures (default docs/figures)
set -euo pipefail

cd "$(dirname "$0")/.."
: "${HYPERSHAPE_BIN:=build/hypershape}" "${DATA_DIR:=results/gallery}" "${OUT_DIR:=docs/figures}"
: "${PRESETS=random2d random2d_p1 easy_random2d ood_random2d one_random2d random3d aug_liver liver one_liver}"
: "${CONFIGS=$(ls configs/examples/*.yaml)}"
BIN=$HYPERSHAPE_BIN
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1

[[ -x "$BIN" ]] || { echo "error: no CLI at $BIN (build it, or set HYPERSHAPE_BIN)" >&2; exit 2; }
mkdir -p "$DATA_DIR" "$OUT_DIR"
seconds_since() { printf '%.1f' "$(echo "$(date +%s.%N) - $1" | bc)"; }

t_all=$(date +%s.%N)
made=() skipped=()
for preset in $PRESETS; do
  base_file=$(sed -n 's/^[[:space:]]*base_file:[[:space:]]*\([^#[:space:]]*\).*/\1/p' "configs/presets/$preset.yaml")
  if [[ -n "$base_file" && ! -f "configs/presets/$base_file" ]]; then
    skipped+=("$preset (no $base_file)")
    continue
  fi
  dir="$DATA_DIR/$preset"
  rm -rf "$dir"
  t0=$(date +%s.%N)
  "$BIN" -q generate --preset "$preset" --mini --progress 0 -o "$dir"
  t_gen=$(seconds_since "$t0")
  t0=$(date +%s.%N)
  /usr/bin/python3 scripts/hypershape_data.py plot "$dir" --gallery 4 -o "$OUT_DIR/${preset}_solutions.png"
  echo "   $preset: generate --mini ${t_gen} s, plot $(seconds_since "$t0") s"
  made+=("$preset")
done
# The example datasets beyond the paper (configs/examples: several tractions with fixed gravity,
# the effects catalogue, the organ under pressure), the 2D ones generated as they are (they are
# small), a 3D one (its preset a 3D one) as its --mini dataset -> <name>_solutions.png.
for config in $CONFIGS; do
  name=$(basename "$config" .yaml)
  dir="$DATA_DIR/$name"
  rm -rf "$dir"
  mini=()
  if grep -Eq '^preset:[[:space:]]*(random3d|aug_liver|liver|one_liver)[[:space:]]*$' "$config"; then mini=(--mini); fi
  t0=$(date +%s.%N)
  "$BIN" -q generate "$config" "${mini[@]}" --progress 0 -o "$dir"
  t_gen=$(seconds_since "$t0")
  /usr/bin/python3 scripts/hypershape_data.py plot "$dir" --gallery 4 -o "$OUT_DIR/${name}_solutions.png"
  echo "   $name: generate ${t_gen} s"
  made+=("$name")
done
echo "figures in $OUT_DIR for: ${made[*]:-none}"
if [[ ${#skipped[@]} -gt 0 ]]; then printf 'skipped: %s\n' "${skipped[@]}"; fi
echo "total $(seconds_since "$t_all") s"
