#!/usr/bin/env bash
# Galleries and metric histograms of the dataset presets -> docs/figures/.
#
#   scripts/make_shape_figures.sh                  # every preset
#   PRESETS="random2d easy_random2d" scripts/make_shape_figures.sh
#
# For each preset, draws and meshes shapes 0..N-1 with `hypershape shapes` (N = 200 for the 2D
# presets, 1 for one_random2d, 30 for the 3D presets), then scripts/shape_gallery.py writes
# docs/figures/<name>_gallery.png (the first 16 shapes) and <name>_histogram.png (all N; none
# for a single shape, e.g. one_random2d).
# A preset whose base surface file is missing is skipped with a note (aug_liver's
# configs/surfaces/organ.stl is made by scripts/make_organ_surface.py). Prints the time of each
# preset and the total.
#
# Environment:
#   HYPERSHAPE_BIN   the CLI (default build/hypershape)
#   NP               MPI ranks (default 2; 1 runs without mpiexec)
#   N2D, N3D         shapes per 2D / 3D preset (default 200 / 30; at least 16 for the gallery)
#   PRESETS          preset names (default: all seven)
#   PRESET_TIMEOUT   seconds per preset, 0 = none (default 900); a preset that runs out is
#                    reported and skipped (a killed run writes no file). 30 Random3D shapes take
#                    about 3.5 min on one core (AugLiver 40 s); a 3D shape whose every draw fails
#                    takes about a minute (20 attempts).
#   SHAPES_DIR       where the .h5 files and the CLI logs go (default results/shapes; ignored)
#   OUT_DIR          figures (default docs/figures)
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"
BIN="${HYPERSHAPE_BIN:-build/hypershape}"
NP="${NP:-2}"
N2D="${N2D:-200}"
N3D="${N3D:-30}"
PRESETS="${PRESETS:-random2d random2d_p1 easy_random2d ood_random2d one_random2d random3d aug_liver}"
PRESET_TIMEOUT="${PRESET_TIMEOUT:-900}"
SHAPES_DIR="${SHAPES_DIR:-results/shapes}"
OUT_DIR="${OUT_DIR:-docs/figures}"
PY=/usr/bin/python3

[[ -x "$BIN" ]] || { echo "error: no CLI at $BIN (build it, or set HYPERSHAPE_BIN)" >&2; exit 2; }
mkdir -p "$SHAPES_DIR" "$OUT_DIR"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OPENBLAS_NUM_THREADS=1

launch=()
if [[ "$NP" -gt 1 ]] && command -v mpiexec >/dev/null; then launch=(mpiexec -n "$NP"); fi
limit=()
if [[ "$PRESET_TIMEOUT" -gt 0 ]]; then limit=(timeout "$PRESET_TIMEOUT"); fi

# "key: value" of a preset's YAML (flat scalar keys only: enough for dim, count, base_file).
yaml_value() { sed -n "s/^[[:space:]]*$2:[[:space:]]*\([^#[:space:]]*\).*/\1/p" "$1" | head -n 1; }

t_all=$(date +%s.%N)
made=() skipped=()
for preset in $PRESETS; do
  cfg="configs/presets/$preset.yaml"
  if [[ ! -f "$cfg" ]]; then skipped+=("$preset (no $cfg)"); continue; fi
  base_file="$(yaml_value "$cfg" base_file)"
  if [[ -n "$base_file" && ! -f "configs/presets/$base_file" ]]; then
    echo "== $preset: skipped, base file configs/presets/$base_file does not exist"
    skipped+=("$preset (no base file $base_file)")
    continue
  fi
  dim="$(yaml_value "$cfg" dim)"
  count="$(yaml_value "$cfg" count)"
  n=$([[ "$dim" == 3 ]] && echo "$N3D" || echo "$N2D")
  (( n > count )) && n=$count
  out="$SHAPES_DIR/$preset.h5"
  echo "== $preset (${dim}D): shapes 0..$((n - 1)) on $NP rank(s)"
  t0=$(date +%s.%N)
  rc=0
  rm -f "$out"
  "${limit[@]}" "${launch[@]}" "$BIN" shapes "$cfg" -n "$n" -o "$out" >"$SHAPES_DIR/$preset.log" 2>&1 || rc=$?
  grep -E "FAILED|error" "$SHAPES_DIR/$preset.log" | cut -c1-160 | head -n 5 | sed 's/^/   /' || true
  t1=$(date +%s.%N)
  secs=$(printf '%.1f' "$(echo "$t1 - $t0" | bc)")
  # rc 3: written, with some failed shapes (the gallery shows them as failed panels).
  if [[ $rc -ne 0 && $rc -ne 3 ]] || [[ ! -f "$out" ]]; then
    echo "   $preset: hypershape exited with $rc after ${secs} s; no figures"
    skipped+=("$preset (hypershape exit $rc after ${secs} s)")
    continue
  fi
  echo "   $preset: $n shapes in ${secs} s (exit $rc)"
  "$PY" scripts/shape_gallery.py "$out" --out-dir "$OUT_DIR"
  made+=("$preset ${secs}s")
done
t_end=$(date +%s.%N)
echo
echo "figures in $OUT_DIR for: ${made[*]:-none}"
if [[ ${#skipped[@]} -gt 0 ]]; then printf 'skipped: %s\n' "${skipped[@]}"; fi
printf 'total %.1f s\n' "$(echo "$t_end - $t_all" | bc)"
