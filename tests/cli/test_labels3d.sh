#!/usr/bin/env bash
# 3D labels (issue 16 part B, drivers/study_labels3d.cpp) on a small case: the unit ball with the
# random3d preset's problem at alpha 5. A graded, per-load-case mesh (P2 h 0.3 refined to 0.1 at
# the clamp rim and 0.05 at p_N), sampled onto the stored h 0.3 mesh's vertices, agrees with a
# uniformly finer solve (P2 h 0.2) to within the two labels' stated errors against the ball's
# reference (docs/ACCURACY.md, "3D labels");
# the label is on the stored mesh's vertices; the per-load mesh raises max|u| at the load above
# the coarse one's. Bad discretisation keys name the allowed ones. ~40 s on a quiet machine (slow).
set -u
bin_dir=$(dirname "${HYPERSHAPE_BIN:?}")
study="$bin_dir/study_labels3d"
[ -x "$study" ] || { echo "FAIL: no $study (build the study_labels3d target)"; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1

msg=$("$study" --scene ball --reference a -d a:h=0.3,bogus=1 --out "$work/x.json" 2>&1); code=$?
[ "$code" -ne 0 ] && grep -q "unknown key 'bogus'" <<<"$msg" && grep -q "allowed: h, surface_h" <<<"$msg" ||
  { echo "FAIL: bad key: exit $code, $msg"; exit 1; }

if ! "$study" --scene ball --reference fine -d fine:h=0.2 -d coarse:h=0.3 \
     -d graded:h=0.3,rim=0.1,load=0.05,label_on=coarse --out "$work/l.json" 2> "$work/log.txt"; then
  echo "FAIL: study_labels3d"; cat "$work/log.txt"; exit 1
fi
cat "$work/log.txt" | cut -c1-160
/usr/bin/python3 - "$work/l.json" <<'PY'
import json, sys
r = {x["name"]: x for x in json.load(open(sys.argv[1]))["results"]}
fails = []
def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what)
    if not cond: fails.append(what)
check(all(x["converged"] for x in r.values()), "every discretisation converged")
g = r["graded"]
check(g["per_load_case_mesh"] and g["label_on"] == "coarse", "the graded mesh is per load case, labelled on the coarse mesh")
check(g["label_vertices"] == r["coarse"]["vertices"], f"the label has the stored mesh's {r['coarse']['vertices']} vertices")
check(g["vertices"] > 2 * r["coarse"]["vertices"], "the per-load mesh is refined")
check(g["max_u"] > r["coarse"]["max_u"], f"max|u| on the per-load mesh {g['max_u']:.4f} > coarse {r['coarse']['max_u']:.4f}")
# Stated errors against the ball's reference (rel L2, volume-weighted, docs/ACCURACY.md "3D
# labels"): u0.2 8.5%; the graded label lies between rim0.3 (6.0%) and load0.3 (7.9%). The two
# differ by 4.3% here (measured); 8% (about twice that, below the sum of their errors) fails if
# the refinement, the sampling onto the stored vertices or the solve breaks.
e = g["error"]["rel_l2_volume"]
check(e < 0.08, f"graded vs uniform h 0.2: rel L2 {e:.4f} < 0.08")
sys.exit(1 if fails else 0)
PY
