#!/usr/bin/env bash
# The validation of the labels' error estimate in docs/ACCURACY.md ("Every label knows its own
# error"): build/study_error_estimate on the accuracy study's scenes and on random Random2D /
# Random3D load cases, then scripts/error_estimate_report.py (table + log-log plot).
#   scripts/error_estimate_study.sh [PART...]    parts: random2d scenes2d p2 random2d_p2 easy_random2d_p2 graded random2d_rim easy_random2d_rim one_random2d_rim relaxation random3d random3d_h03 scenes3d report
#                                                (default: all; each appends to docs/error_estimate/PART.jsonl)
# One rank, OPENBLAS_NUM_THREADS=1; references with MUMPS (-ref_ prefix). Runtime on the shared
# 2-core VM: random2d ~10 min, scenes2d ~5, p2 ~10, random3d/scenes3d ~10 each.
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${BIN:-build/study_error_estimate}
OUT=${OUT:-docs/error_estimate}
mkdir -p "$OUT" docs/figures
export OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1
ref=(-ref_pc_factor_mat_solver_type mumps)
parts=("$@")
[ ${#parts[@]} -gt 0 ] || parts=(random2d scenes2d p2 random2d_p2 easy_random2d_p2 random3d scenes3d report)
for part in "${parts[@]}"; do
  case $part in
    random2d)  # 17 Random2D shapes x 3 load cases at P1 h 0.04 (the random2d_p1 preset, random2d before 2026-11-28)
      "$BIN" --preset random2d_p1 --shapes $(seq 0 16) --loads 3 --out "$OUT/random2d.jsonl" -- "${ref[@]}" ;;
    scenes2d)  # the accuracy study's 2D scenes at their presets' settings, targets 0.1 0.3 0.5
      for s in disk r2d-0 r2d-1 ood-0 easy-0; do "$BIN" --scene $s --out "$OUT/scenes2d.jsonl" -- "${ref[@]}"; done ;;
    p2)        # P2 on the same scenes at h 0.08 (references P2 at h 0.04 and 0.02)
      for s in disk r2d-0 r2d-1 ood-0; do "$BIN" --scene $s --degree 2 --h 0.08 --out "$OUT/p2.jsonl" -- "${ref[@]}"; done ;;
    random2d_p2)  # Random2D shapes no other run used (20-27), P2 at h 0.08, 2 load cases each
      "$BIN" --preset random2d_p1 --degree 2 --h 0.08 --shapes $(seq 20 27) --loads 2 --out "$OUT/random2d_p2.jsonl" -- "${ref[@]}" ;;
    easy_random2d_p2)  # EasyRandom2D at its preset's P2 h 0.12, the same unused shapes
      "$BIN" --preset easy_random2d --shapes $(seq 20 27) --loads 2 --out "$OUT/easy_random2d_p2.jsonl" -- "${ref[@]}" ;;
    graded)    # the same on meshes graded towards the clamp ends (h/8, h/32 there), and the estimate
               # with Newton to tolerance on the fine mesh (estimate only: joined with the truths above)
      mkdir -p "$OUT/graded"
      "$BIN" --preset random2d_p1 --degree 2 --h 0.08 --graded 0.125 --shapes $(seq 20 27) --loads 2 \
        --out "$OUT/graded/random2d_p2_graded0.125.jsonl" -- "${ref[@]}"
      "$BIN" --preset random2d_p1 --degree 2 --h 0.08 --graded 0.03125 --shapes 20 21 22 23 --loads 2 \
        --out "$OUT/graded/random2d_p2_graded0.03125.jsonl" -- "${ref[@]}"
      "$BIN" --preset random2d_p1 --degree 2 --h 0.08 --shapes $(seq 20 27) --loads 2 --fine-newton --estimate-only \
        --out "$OUT/graded/random2d_p2_fine_newton_estimate_only.jsonl"
      "$BIN" --preset random2d_p1 --degree 2 --h 0.08 --graded 0.125 --shapes $(seq 20 27) --loads 2 --fine-newton \
        --estimate-only --out "$OUT/graded/random2d_p2_graded0.125_fine_newton_estimate_only.jsonl" ;;
    random2d_rim)  # the random2d preset's mesh graded to h/32 at the clamp ends (mesh.rim 0.00375, since
                   # 2026-11-29) against the same mesh ungraded (the preset before) and at h/16: shapes 20-27
      mkdir -p "$OUT/rim"
      "$BIN" --preset random2d --shapes $(seq 20 27) --loads 2 --out "$OUT/rim/random2d.jsonl" -- "${ref[@]}"
      for g in 0 0.0625; do
        "$BIN" --preset random2d --graded $g --shapes $(seq 20 27) --loads 2 --out "$OUT/rim/random2d_graded$g.jsonl" -- "${ref[@]}"
      done ;;
    easy_random2d_rim)  # the same for easy_random2d (not graded: its preset; h/16, h/32)
      mkdir -p "$OUT/rim"
      for g in 0 0.0625 0.03125; do
        "$BIN" --preset easy_random2d --graded $g --shapes $(seq 20 27) --loads 2 --out "$OUT/rim/easy_random2d_graded$g.jsonl" -- "${ref[@]}"
      done ;;
    random3d)  # Random3D shapes (P2) as the preset solves them, coarser (mesh.h 0.5) so that a
               # reference two refinements finer stays within reach of one core
      "$BIN" --preset random3d --h 0.5 --shapes 0 1 2 3 4 --loads 2 --levels 2 --out "$OUT/random3d.jsonl" -- "${ref[@]}" ;;
    random3d_h03)  # the preset's own mesh (mesh.h 0.3), one reference refinement (~35k unknowns)
      "$BIN" --preset random3d --shapes $(seq 0 9) --loads 1 --levels 1 --out "$OUT/random3d_h03.jsonl" -- "${ref[@]}" ;;
    scenes3d)
      "$BIN" --scene ball --h 0.5 --levels 2 --out "$OUT/scenes3d.jsonl" -- "${ref[@]}" ;;
    one_random2d_rim)  # one_random2d's family (P2 h 0.08) as drawn and graded to 0.00375 (the preset since
                       # 2026-11-29), shapes 20-25 of its seed
      mkdir -p "$OUT/rim"
      for g in 0 0.046875; do
        "$BIN" --preset one_random2d --graded $g --shapes $(seq 20 25) --loads 2 --out "$OUT/rim/one_random2d_graded$g.jsonl" -- "${ref[@]}"
      done ;;
    relaxation)  # the estimate alone (--estimate-only) on the cases above with a truth, with and without
                 # local relaxation of the fine state (since 2026-11-29), joined with those truths
      R="$OUT/relaxation"
      mkdir -p "$R"
      for t in relax off; do
        o=()
        [ $t = off ] && o=(-error_estimate_no_relaxation)
        rm -f "$R"/*_$t.jsonl
        E=(--estimate-only -- "${o[@]}")
        "$BIN" --preset random2d_p1 --shapes $(seq 0 16) --loads 3 --out "$R/random2d_$t.jsonl" "${E[@]}"
        for s in disk r2d-0 r2d-1 ood-0 easy-0; do "$BIN" --scene $s --out "$R/scenes2d_$t.jsonl" "${E[@]}"; done
        for s in disk r2d-0 r2d-1 ood-0; do "$BIN" --scene $s --degree 2 --h 0.08 --out "$R/p2_$t.jsonl" "${E[@]}"; done
        "$BIN" --preset random2d_p1 --degree 2 --h 0.08 --shapes $(seq 20 27) --loads 2 --out "$R/random2d_p2_$t.jsonl" "${E[@]}"
        for g in 0 0.0625; do
          "$BIN" --preset random2d --graded $g --shapes $(seq 20 27) --loads 2 --out "$R/rim_random2d_graded${g}_$t.jsonl" "${E[@]}"
        done
        "$BIN" --preset random2d --shapes $(seq 20 27) --loads 2 --out "$R/rim_random2d_$t.jsonl" "${E[@]}"
        for g in 0 0.0625 0.03125; do
          "$BIN" --preset easy_random2d --graded $g --shapes $(seq 20 27) --loads 2 --out "$R/rim_easy_random2d_graded${g}_$t.jsonl" "${E[@]}"
        done
        "$BIN" --preset random3d --shapes $(seq 0 9) --loads 1 --out "$R/random3d_$t.jsonl" "${E[@]}"
        echo "== local relaxation: $t"
        /usr/bin/python3 scripts/error_estimate_report.py "$R"/*_$t.jsonl --truths "$OUT"/rim/*.jsonl \
          $(ls "$OUT"/*.jsonl | grep -v 'random3d_h03\|s022_one_step')
      done ;;
    report)
      /usr/bin/python3 scripts/error_estimate_report.py "$OUT"/*.jsonl --plot docs/figures/error_estimate.png ;;
    *) echo "unknown part $part" >&2; exit 2 ;;
  esac
done
