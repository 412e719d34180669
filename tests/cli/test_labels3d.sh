#!/usr/bin/env bash
# 3D labels (issue 16 part B, drivers/study_labels3d.cpp) on a small case: the unit ball with the
# random3d preset's problem at alpha 5. A graded, per-load-case mesh (P2 h 0.3 refined to 0.1 at
# the clamp rim and 0.05 at p_N), sampled onto the stored h 0.3 mesh's vertices, agrees with a
# uniformly finer solve (P2 h 0.2) to within the two labels' stated errors against the ball's
# reference (docs/ACCURACY.md, "3D labels");
# the label is on the stored mesh's vertices; the per-load mesh raises max|u| at the load above
# the coarse one's. Bad discretisation keys and scenes name the allowed ones; a factory load case
# (r3d:SEED:SHAPE:LOAD) is a scene, and share= (pointwise_share) lies between its two materials. A sphere scene accepts the
# datasets' mesh.surface_h / mesh.rim (hypershape solve). ~40 s on a quiet machine (slow).
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

msg=$("$study" --scene r3d:1:2 --reference a -d a:h=0.3 --out "$work/x.json" 2>&1); code=$?
[ "$code" -ne 0 ] && grep -q "allowed: ball, r3d-0, r3d:SEED:SHAPE:LOAD" <<<"$msg" && [ ! -e "$work/x.json" ] ||
  { echo "FAIL: bad scene: exit $code, $msg"; exit 1; }
echo "ok   a bad scene names the allowed ones"

# A factory load case as a scene (r3d:SEED:SHAPE:LOAD) and neo_hookean's pointwise_share (share=):
# half the bulk energy pointwise gives a label between the mean-dilatation and pointwise ones.
"$study" --scene r3d:90210:0:1 --reference m -d m:h=0.3,dilatation=mean -d s:h=0.3,dilatation=mean,share=0.5 \
  -d p:h=0.3 --out "$work/f.json" 2> "$work/f.txt" || { echo "FAIL: study_labels3d r3d:90210:0:1"; cat "$work/f.txt"; exit 1; }
/usr/bin/python3 - "$work/f.json" <<'PY' || exit 1
import json, sys
d = json.load(open(sys.argv[1]))
r = {x["name"]: x["error"]["label_max_u"] for x in d["results"]}
ok = r["p"] < r["s"] < r["m"]
print(("ok   " if ok else "FAIL ") + f"r3d:90210:0:1: max|u| pointwise {r['p']:.4f} < share 0.5 {r['s']:.4f} < mean {r['m']:.4f}")
sys.exit(0 if ok else 1)
PY

# A scene accepts the datasets' 3D discretisation keys (mesh.surface_h, mesh.rim): the ball is
# then meshed as the factory meshes a shape, refined at the rim; a 2D scene rejects them by name.
scene() {
  printf 'geometry: {base: %s}\nmesh: %s\neffects:\n  neo_hookean: {E: 500, nu: 0.49}\n  dirichlet_patch: {center: %s, radius: 0.4}\nload: {alpha: 5}\n' "$@"
}
vertices() { "${HYPERSHAPE_BIN}" solve "$1" -o "$work/s.h5" 2>&1 | sed -n 's/.*P1: \([0-9]*\) vertices.*/\1/p'; }
scene sphere "{degree: 1, h: 0.3}" "[1, 0, 0]" > "$work/plain.yaml"
scene sphere "{degree: 1, h: 0.3, surface_h: 0.3, rim: 0.1}" "[1, 0, 0]" > "$work/rim.yaml"
n_plain=$(vertices "$work/plain.yaml"); n_rim=$(vertices "$work/rim.yaml")
[ -n "$n_plain" ] && [ -n "$n_rim" ] && [ "$n_rim" -gt "$n_plain" ] ||
  { echo "FAIL: scene mesh.rim: $n_plain vertices without, $n_rim with"; exit 1; }
echo "ok   scene mesh {surface_h, rim}: $n_plain -> $n_rim vertices"
# A circle scene takes mesh.rim (the patch ends' size, as the 2D datasets' key) but not surface_h.
scene circle "{degree: 1, h: 0.1, surface_h: 0.05}" "[1, 0]" > "$work/bad.yaml"
msg=$("${HYPERSHAPE_BIN}" solve "$work/bad.yaml" -o "$work/b.h5" 2>&1) && { echo "FAIL: surface_h on a 2D scene accepted"; exit 1; }
grep -q "surface_h" <<<"$msg" && grep -q "base: sphere" <<<"$msg" || { echo "FAIL: surface_h on a 2D scene: $msg"; exit 1; }
echo "ok   scene mesh.surface_h on a circle rejected: $(tail -1 <<<"$msg")"

# r3d-0 is Random3D shape 0 as drawn: its patch centre and load case stay what the study's
# tables were measured on, whatever the random3d preset's own mesh (a rim there redraws shape 0).
# An option whose mesh cannot be made (rim 0.05 on a 0.3 surface folds a triangle there) is
# recorded as failed and the study goes on.
"$study" --scene r3d-0 --reference a -d a:h=0.3 -d bad:h=0.3,rim=0.05 -d b:h=0.3 --out "$work/r.json" 2> "$work/r.txt" ||
  { echo "FAIL: study_labels3d r3d-0"; cat "$work/r.txt"; exit 1; }
/usr/bin/python3 - "$work/r.json" <<'PY' || exit 1
import json, sys
d = json.load(open(sys.argv[1]))
want = {"p_D": [0.7812941698929541, -0.45478935312820246, 0.0683569092108644],
        "p_N": [0.6654219894171893, 0.6512010878199574, 0.2512306840294596]}
bad = [k for k, v in want.items() if max(abs(a - b) for a, b in zip(d[k], v)) > 1e-12]
print(("FAIL " if bad else "ok   ") + f"r3d-0 is shape 0 as the tables measured it (p_D {d['p_D']})")
r = {x["name"]: x for x in d["results"]}
went_on = (not r["bad"]["converged"] and r["bad"]["reason"].startswith("failed: remesh_surface")
           and r["b"]["converged"] and r["b"]["error"]["rel_l2_volume"] < 1e-12)
print(("ok   " if went_on else "FAIL ") + f"an option whose mesh fails is recorded ({r['bad']['reason'][:60]}...) and the study goes on")
sys.exit(1 if bad or not went_on else 0)
PY

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
