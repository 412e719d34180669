#!/usr/bin/env bash
# The accuracy/time study (issue 6, docs/ACCURACY.md): runs drivers/study_accuracy and makes the
# Pareto plots and tables.
#   scripts/study_accuracy.sh            the full study (2D and 3D scenes; about 20 min on one core)
#   scripts/study_accuracy.sh --tiny     the CI version (the disk, coarse; about a minute)
#   scripts/study_accuracy.sh --full --dims 2    any other driver option (see study_accuracy --help)
# Environment: BUILD (default build), OUT (default results/study_accuracy.json, or
# results/study_accuracy_tiny.json with --tiny), FIG_DIR (default docs/figures; --tiny writes
# into results/figures so the committed figures stay those of the full study).
# Output: $OUT, ${OUT%.json}.md (tables + findings), $FIG_DIR/accuracy_pareto_{2d,3d}.png.
# Timings are wall times on a machine that may be shared: run it on a quiet machine.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${BUILD:-build}
tiny=0
for a in "$@"; do [ "$a" = "--tiny" ] && tiny=1; done
if [ "$tiny" = 1 ]; then
  out=${OUT:-results/study_accuracy_tiny.json}
  fig_dir=${FIG_DIR:-results/figures}
  suffix=_tiny
else
  out=${OUT:-results/study_accuracy.json}
  fig_dir=${FIG_DIR:-docs/figures}
  suffix=
fi
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1
if [ ! -x "$build/study_accuracy" ]; then
  echo "no $build/study_accuracy: build it first (cmake --build $build --target study_accuracy)" >&2
  exit 2
fi
mkdir -p "$(dirname "$out")"
"$build/study_accuracy" --out "$out" "$@"
/usr/bin/python3 scripts/plot_accuracy.py "$out" --fig-dir "$fig_dir" --suffix "$suffix" > /dev/null
echo "[study] $out, ${out%.json}.md, $fig_dir/accuracy_pareto_*d$suffix.png"
