#!/usr/bin/env bash
# The 3D label study (issue 16 part B, docs/ACCURACY.md "3D labels"): a converged reference on
# the ball and on Random3D shape 0 (the random3d preset's problem at alpha 5), the ladder that
# states its error, and the options a dataset could label with.
#   scripts/study_labels3d.sh [ball|r3d-0 ...]      (default: both; ~15-30 min each on a shared 2-core VM)
#   DILATATION=mean scripts/study_labels3d.sh        (the mean-dilatation element's study)
#   STUDY=large_loads | STUDY=share scripts/study_labels3d.sh   (alpha 15/30; pointwise_share)
#   STUDY=surface022 scripts/study_labels3d.sh       (the random3d preset's mesh of 2026-11-26)
# Output: results/labels3d/<scene>.json, results/labels3d/<scene>_ref*.h5 (for
# scripts/check_labels3d_dolfinx.py), and the tables (scripts/labels3d_table.py).
set -euo pipefail
cd "$(dirname "$0")/.."
build=${BUILD:-build}
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1
scenes=("$@")
[ ${#scenes[@]} -eq 0 ] && scenes=(ball r3d-0)
mkdir -p results/labels3d
if [ "${STUDY:-}" = large_loads ] || [ "${STUDY:-}" = share ]; then
  # docs/ACCURACY.md, "Labels that invert inside a cell": the preset's options at the dataset's
  # large loads (alpha 15 and 30 on r3d-0), and neo_hookean's pointwise_share (share=) at alpha
  # 5, each against refm0.025 (0.5-0.7% off refm0.0125 at alpha 5; the pointwise ref0.025 beside
  # it). STUDY=large_loads | STUDY=share scripts/study_labels3d.sh [scenes]
  m=",dilatation=mean"; r="rim=0.1"
  ref="refm0.025:surface_h=0.1,interior_h=0.3,rim=0.025,load=0.025,grading=0.4$m"
  for scene in "${scenes[@]}"; do
    if [ "$STUDY" = large_loads ]; then
      for a in 15 30; do
        "$build/study_labels3d" --scene "$scene" --alpha $a --reference refm0.025 -d "$ref" \
          -d ref0.025:surface_h=0.1,interior_h=0.3,rim=0.025,load=0.025,grading=0.4 \
          -d rim0.25m10:h=0.25,$r$m -d rim0.25p10:h=0.25,$r -d u0.3:h=0.3 \
          -d s0.2i0.3rim10m:surface_h=0.2,interior_h=0.3,$r$m --out "results/labels3d/${scene}_alpha$a.json"
      done
    else
      "$build/study_labels3d" --scene "$scene" --alpha 5 --reference refm0.025 -d "$ref" \
        -d rim0.25m10:h=0.25,$r$m -d rim0.25m10s05:h=0.25,$r$m,share=0.05 -d rim0.25m10s10:h=0.25,$r$m,share=0.1 \
        -d rim0.25m10s20:h=0.25,$r$m,share=0.2 -d rim0.25p10:h=0.25,$r \
        -d s0.2i0.3rim10m:surface_h=0.2,interior_h=0.3,$r$m -d s0.2i0.3rim10s05:surface_h=0.2,interior_h=0.3,$r$m,share=0.05 \
        --out "results/labels3d/${scene}_share_alpha5.json"
    fi
  done
  exit 0
fi
if [ "${STUDY:-}" = surface022 ]; then
  # docs/ACCURACY.md, "The random3d preset moved again": surfaces of 0.2-0.22 over a 0.25-0.35
  # interior, the rim at 0.1-0.125, against refm0.0125 -> results/labels3d/<scene>_mean_s022.json
  m=",dilatation=mean"
  for scene in "${scenes[@]}"; do
    "$build/study_labels3d" --scene "$scene" --reference refm0.0125 \
      -d refm0.0125:surface_h=0.1,interior_h=0.3,rim=0.0125,load=0.0125,grading=0.4$m \
      -d rim0.25m10:h=0.25,rim=0.1$m -d s0.2i0.3rim10m:surface_h=0.2,interior_h=0.3,rim=0.1$m \
      -d s0.22i0.3rim10m:surface_h=0.22,interior_h=0.3,rim=0.1$m -d s0.2i0.3rim12m:surface_h=0.2,interior_h=0.3,rim=0.125$m \
      -d s0.22i0.3rim12m:surface_h=0.22,interior_h=0.3,rim=0.125$m -d s0.22i0.25rim10m:surface_h=0.22,interior_h=0.25,rim=0.1$m \
      -d s0.2i0.35rim12m:surface_h=0.2,interior_h=0.35,rim=0.125$m \
      --out "results/labels3d/${scene}_mean_s022.json" 2>&1 | tee "results/labels3d/${scene}_mean_s022.log"
  done
  exit 0
fi
if [ "${DILATATION:-}" = mean ]; then
  # The same with the mean-dilatation element (docs/ACCURACY.md, "3D labels with the
  # mean-dilatation element"): its reference ladder, the pointwise reference beside it, and the
  # options: DILATATION=mean scripts/study_labels3d.sh -> results/labels3d/<scene>_mean.json
  m=",dilatation=mean"
  for scene in "${scenes[@]}"; do
    "$build/study_labels3d" --scene "$scene" --reference refm0.0125 \
      -d refm0.0125:surface_h=0.1,interior_h=0.3,rim=0.0125,load=0.0125,grading=0.4$m \
      -d ref0.0125:surface_h=0.1,interior_h=0.3,rim=0.0125,load=0.0125,grading=0.4 \
      -d refm0.025:surface_h=0.1,interior_h=0.3,rim=0.025,load=0.025,grading=0.4$m \
      -d refm0.05:surface_h=0.1,interior_h=0.3,rim=0.05,load=0.05,grading=0.4$m \
      -d u0.3:h=0.3 -d u0.3m:h=0.3$m -d u0.25m:h=0.25$m -d u0.2m:h=0.2$m \
      -d rim0.3m:h=0.3,rim=0.075$m -d rim0.25m:h=0.25,rim=0.075$m -d rim0.2m:h=0.2,rim=0.075$m \
      -d rim0.3m15:h=0.3,rim=0.15$m -d rim0.3m10:h=0.3,rim=0.1$m -d rim0.25m10:h=0.25,rim=0.1$m \
      -d rim0.2m5:h=0.2,rim=0.05$m -d u0.2:h=0.2 -d rim0.2:h=0.2,rim=0.075 -d s0.15rimm:surface_h=0.15,interior_h=0.3,rim=0.05$m \
      -d s0.1m:surface_h=0.1,interior_h=0.3$m -d s0.1rimm:surface_h=0.1,interior_h=0.3,rim=0.05$m \
      --out "results/labels3d/${scene}_mean.json" 2>&1 | tee "results/labels3d/${scene}_mean.log"
  done
  exit 0
fi
for scene in "${scenes[@]}"; do
  # The reference ladder (local sizes halved at the clamp rim and at p_N; the surface as drawn,
  # 0.1) and the options. ref0.0125 is the reference; ref0.025 and ref0.05 give its error.
  "$build/study_labels3d" --scene "$scene" --reference ref0.0125 --write results/labels3d \
    -d ref0.0125:surface_h=0.1,interior_h=0.3,rim=0.0125,load=0.0125,grading=0.4 \
    -d ref0.025:surface_h=0.1,interior_h=0.3,rim=0.025,load=0.025,grading=0.4 \
    -d ref0.05:surface_h=0.1,interior_h=0.3,rim=0.05,load=0.05,grading=0.4 \
    -d u0.3:h=0.3 -d u0.25:h=0.25 -d u0.2:h=0.2 -d u0.15:h=0.15 \
    -d rim0.3:h=0.3,rim=0.075 \
    -d load0.3:h=0.3,load=0.03,label_on=u0.3 \
    -d s0.1:surface_h=0.1,interior_h=0.3 \
    -d s0.1rim:surface_h=0.1,interior_h=0.3,rim=0.05 \
    -d s0.1rimload:surface_h=0.1,interior_h=0.3,rim=0.05,load=0.03,label_on=s0.1rim \
    --out "results/labels3d/$scene.json" 2>&1 | tee "results/labels3d/$scene.log"
done
