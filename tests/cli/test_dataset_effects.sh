#!/usr/bin/env bash
# A dataset that chooses its effects (configs/examples/multi_load2d.yaml, shrunk: 3 shapes x 2
# load cases): three Gaussian tractions per load case scaled by the tuned alpha, gravity fixed
# under them, E drawn per shape, a traction width drawn per load case.
#  - passes `hypershape_data.py check`; identical (bit for bit) on 1 and 2 ranks and as a
#    2-task array merged by `hypershape index`, and to 1e-9 with a solver group of 2 ranks;
#  - drawn parameters in the shards (params/...), the scene in every shard, the channels
#    traction and body_force at the nodes and on the grid; the torch Datasets serve them;
#  - `hypershape solve` on the same scene (the shape's mesh written as a .msh, the drawn
#    values fixed) gives the same solution as `generate`;
#  - a count of tractions drawn per load case (copies beyond it inactive);
#  - a scene without a traction stores no traction, p_N, g or I_N (only the effects called for);
#  - bad scenes stop before any work: exit code 2, the key path named, nothing written.
# Needs HYPERSHAPE_BIN and HYPERSHAPE_SOURCE_DIR (set by CTest).
. "$(dirname "$0")/lib.sh"
export PYTHONPATH="$src/scripts${PYTHONPATH:+:$PYTHONPATH}"

sed -e 's/shapes: {count: 4, h: 0.08}/shapes: {count: 3, h: 0.1}/; s/count: 4, target/count: 2, target/' \
    -e 's/grid_size: 32/grid_size: 16/; s/shard_size: 2/shard_size: 1/' \
    "$src/configs/examples/multi_load2d.yaml" > "$work/multi.yaml"
gen() { "$bin" -q generate "$work/multi.yaml" --progress 0 "$@"; }
gen -o "$work/np1" || fail "1-rank run"
mpiexec -n 2 "$bin" -q generate "$work/multi.yaml" --progress 0 -o "$work/np2" || fail "2-rank run"
mpiexec -n 2 "$bin" -q generate "$work/multi.yaml" --progress 0 --group-size 2 -o "$work/g2" || fail "group of 2"
for t in 0 1; do gen --task-index $t --task-count 2 -o "$work/array" || fail "task $t"; done
"$bin" -q index "$work/array" || fail "index of the array"
/usr/bin/python3 "$src/scripts/hypershape_data.py" check "$work/np1" >/dev/null && ok "hypershape_data.py check" || fail "check"
for d in np2 array; do
  if compare "$work/np1" "$work/$d" >/dev/null; then ok "1 rank == $d, bit for bit"; else fail "1 rank != $d"; fi
done
# A solver group of 2 ranks (METIS partition; the fixed load assembled on both) sums in another order.
if compare "$work/np1" "$work/g2" --rtol 1e-9 >/dev/null; then ok "1 rank == a group of 2 ranks, to 1e-9"; else fail "1 rank != g2"; fi

/usr/bin/python3 - "$work/np1" <<'PY' && ok "params, scene and channels stored; torch Datasets serve traction and body_force" || fail "stored data"
import sys
import numpy as np
import hypershape_data as hd
import hypershape_torch as ht
ds = hd.open_dataset(sys.argv[1])
assert ds.channels == ["traction", "body_force"], ds.channels
assert "gaussian_traction:" in ds.scene_text and "scale: fixed" in ds.scene_text, ds.scene_text
Es = set()
for sid, lid in ds.keys():
    s = ds.sample(sid, lid)
    p = s.params
    assert 400 <= p["neo_hookean/E"] <= 600, p
    assert p["gaussian_traction.2/gamma"] in (0.15, 0.3), p
    assert p["gaussian_traction.1/center"].shape == (2,), p
    Es.add(p["neo_hookean/E"])
    b = s.point_cloud["body_force"]
    assert np.allclose(b, [0.0, -2.0]), b[:3]                 # fixed: not scaled by alpha
    t = s.point_cloud["traction"]
    assert np.all(t[~s.neumann_mask] == 0) and np.abs(t).max() > 0
    assert s.grid["body_force"].shape == (16, 16, 2)
assert len(Es) == len(ds.shape_ids()), Es                   # one E per shape
g = ht.GridDataset(sys.argv[1], "train", normalize="channelwise")
assert g.x_channels == ["sdf", "dirichlet_distance", "traction_x", "traction_y", "body_force_x", "body_force_y"]
assert g[0]["x"].shape == (6, 16, 16)
pc = ht.PointCloudDataset(sys.argv[1], "train")
assert pc[0]["x"].shape[1] == 6
PY

# ---- only the effects called for: no traction, a body force tuned by alpha -------------------
printf 'preset: random2d\nname: gravity_only\nseed: 5\nshapes: {count: 1, h: 0.1}\nloads: {count: 2}\nrepresentations: {grid_size: 8}\neffects:\n  neo_hookean: {E: 500, nu: 0.49}\n  dirichlet_patch: {radius: 0.5}\n  body_force: {value: [0.0, -1.0]}\n' > "$work/gravity.yaml"
"$bin" -q generate "$work/gravity.yaml" --progress 0 -o "$work/gravity" || fail "gravity-only run"
/usr/bin/python3 - "$work/gravity" <<'PY' && ok "no traction in the scene: no traction, p_N, g or I_N stored; body_force scaled by alpha" || fail "gravity only"
import sys, h5py, numpy as np
import hypershape_data as hd, hypershape_torch as ht
g = h5py.File(f"{sys.argv[1]}/shards/shard-000000.h5")["shapes/000000/loads"]
assert not any(k in g for k in ("traction", "grid_traction", "p_n", "g", "traction_normaliser")), list(g)
assert list(g["status"][:]) == [1, 1], g["reason"][:]
b, alpha = g["body_force"][...], g["alpha"][...]
assert np.allclose(b[:, :, 1], -alpha[:, None]) and np.all(b[:, :, 0] == 0)
assert hd.open_dataset(sys.argv[1]).channels == ["body_force"]
assert ht.GridDataset(sys.argv[1], None).x_channels == ["sdf", "dirichlet_distance", "body_force_x", "body_force_y"]
PY

# ---- a count of tractions drawn per load case ------------------------------------------------
count_cfg() {  # $1: the gaussian_traction entry
  printf 'preset: random2d\nname: count\nseed: 9\nshapes: {count: 1, h: 0.1}\nloads: {count: 6}\nrepresentations: {grid_size: 8}\neffects:\n  neo_hookean: {E: 500, nu: 0.49}\n  dirichlet_patch: {radius: 0.5}\n  gaussian_traction: %s\n' "$1"
}
count_cfg '{gamma: 0.2, count: {choice: [1, 2, 3], sample: load}}' > "$work/count.yaml"
count_cfg '{gamma: 0.2}' > "$work/one.yaml"
"$bin" -q generate "$work/count.yaml" --progress 0 -o "$work/count" || fail "count run"
"$bin" -q generate "$work/one.yaml" --progress 0 -o "$work/one" || fail "one-traction run"
/usr/bin/python3 - "$work/count" "$work/one" <<'PY' && ok "a drawn count of tractions: load cases with count 1 are the one-traction dataset's (to 1e-6), the others not" || fail "drawn count"
import sys, h5py, numpy as np
a = h5py.File(f"{sys.argv[1]}/shards/shard-000000.h5")["shapes/000000"]
b = h5py.File(f"{sys.argv[2]}/shards/shard-000000.h5")["shapes/000000"]
n = a["params/gaussian_traction/count"][...]
assert set(n) <= {1, 2, 3} and len(set(n)) > 1, n
assert list(a["loads/status"][:]) == [1] * 6 and list(b["loads/status"][:]) == [1] * 6
for l, k in enumerate(n):
    ua, ub = a["loads/displacement"][l], b["loads/displacement"][l]
    d = np.abs(ua - ub).max() / np.abs(ub).max()
    assert (d < 1e-6) == (k == 1), (l, k, d)
    ta, tb = a["loads/traction"][l], b["loads/traction"][l]
    assert (np.abs(ta - tb).max() <= 1e-6 * np.abs(tb).max()) == (k == 1), (l, k)
PY

# ---- solve == generate on the same scene -----------------------------------------------------
/usr/bin/python3 - "$work/np1" "$work" <<'PY' || fail "writing the scene of shape 0, load 0"
import sys, h5py
ds, work = sys.argv[1], sys.argv[2]
g = h5py.File(f"{ds}/shards/shard-000000.h5")["shapes/000000"]
nodes, cells = g["nodes"][...], g["cells"][...]
with open(f"{work}/shape0.msh", "w") as f:
    f.write("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n%d\n" % len(nodes))
    for i, x in enumerate(nodes):
        f.write("%d %.17g %.17g 0\n" % (i + 1, x[0], x[1]))
    f.write("$EndNodes\n$Elements\n%d\n" % len(cells))
    for k, c in enumerate(cells):
        f.write("%d 2 2 1 1 %d %d %d\n" % (k + 1, c[0] + 1, c[1] + 1, c[2] + 1))
    f.write("$EndElements\n")
l, p = g["loads"], g["params"]
v = lambda a: "[%.17g, %.17g]" % tuple(a)
pd = g.attrs["dirichlet_center"][:2]
tr = [(l["p_n"][0], l["g"][0], 0.2), (p["gaussian_traction.1/center"][0], p["gaussian_traction.1/direction"][0], 0.2),
      (p["gaussian_traction.2/center"][0], p["gaussian_traction.2/direction"][0], p["gaussian_traction.2/gamma"][0])]
with open(f"{work}/scene0.yaml", "w") as f:
    f.write("geometry: {base: file, file: shape0.msh}\nmesh: {degree: 1}\neffects:\n")
    f.write("  neo_hookean: {E: %.17g, nu: 0.49}\n" % p["neo_hookean/E"][0])
    f.write("  dirichlet_patch: {center: %s, radius: 0.5}\n  gaussian_traction:\n" % v(pd))
    for c, d, gm in tr:
        f.write("    - {center: %s, direction: %s, gamma: %.17g}\n" % (v(c), v(d), gm))
    f.write("  body_force: {value: [0, -2], scale: fixed}\nload: {target: %.17g}\n" % l["target"][0])
PY
"$bin" -q solve "$work/scene0.yaml" -o "$work/solve0.h5" >/dev/null || fail "solve of the same scene"
/usr/bin/python3 - "$work/np1" "$work/solve0.h5" <<'PY' && ok "solve == generate on the same scene (u to 1e-6 of max|u|, alpha to 1e-6)" || fail "solve != generate"
import sys, h5py, numpy as np
g = h5py.File(f"{sys.argv[1]}/shards/shard-000000.h5")["shapes/000000"]
s = h5py.File(sys.argv[2])
xa, ua = g["nodes"][...], g["loads/displacement"][0]
xb, ub = s["mesh/nodes"][...], s["fields/displacement"][...]
ia, ib = np.lexsort(xa.T[::-1]), np.lexsort(xb.T[::-1])
assert np.abs(xa[ia] - xb[ib]).max() < 1e-12
err = np.abs(ua[ia] - ub[ib]).max() / np.abs(ua).max()
da = abs(s.attrs["alpha"] - g["loads/alpha"][0]) / g["loads/alpha"][0]
print("max |u_solve - u_generate| / max|u|:", err, " alpha:", da)
assert err < 1e-6 and da < 1e-6, (err, da)
PY

# ---- bad scenes: exit code 2, the key path named, nothing written ----------------------------
head_cfg='preset: random2d\nname: bad\nseed: 1\nshapes: {count: 1, h: 0.1}\nloads: {count: 1}'
good_effects='  dirichlet_patch: {radius: 0.5}\n  gaussian_traction: {gamma: 0.2}'
bad() {  # name, expected text, effects block (printf escapes), [extra top-level lines]
  local name=$1 key=$2 cfg="$work/bad_$1.yaml" out="$work/bad_$1_out" msg code
  printf "$head_cfg\n${4:-}effects:\n$3\n" > "$cfg"
  msg=$("$bin" generate "$cfg" --progress 0 -o "$out" 2>&1 >/dev/null); code=$?
  if [ "$code" -ne 2 ]; then fail "$name: exit $code (want 2): $msg"; return; fi
  if ! grep -qF -- "$key" <<<"$msg"; then fail "$name: message does not name '$key': $msg"; return; fi
  if [ -e "$out" ]; then fail "$name: left output behind"; return; fi
  ok "$name: $msg"
}
nh='  neo_hookean: {E: 500, nu: 0.49}'
bad unknown_effect  "effects.magnetic: unknown effect"   "$nh\n$good_effects\n  magnetic: {B: 1}"
bad unknown_key     "effects.gaussian_traction.gama"     "$nh\n  dirichlet_patch: {radius: 0.5}\n  gaussian_traction: {gamma: 0.2, gama: 0.2}"
bad distribution    "effects.neo_hookean.E"              "  neo_hookean: {E: {normal: [500, 50]}, nu: 0.49}\n$good_effects"
bad uniform_order   "effects.neo_hookean.E.uniform"      "  neo_hookean: {E: {uniform: [600, 400]}, nu: 0.49}\n$good_effects"
bad sample_kind     "effects.neo_hookean.E.sample"       "  neo_hookean: {E: {uniform: [400, 600], sample: batch}, nu: 0.49}\n$good_effects"
bad nu_range        "effects.neo_hookean.nu"             "  neo_hookean: {E: 500, nu: {uniform: [0.3, 0.6]}}\n$good_effects"
bad per_load_E      "effects.neo_hookean.E: drawn per load case" "  neo_hookean: {E: {uniform: [400, 600], sample: load}, nu: 0.49}\n$good_effects"
bad two_materials   "effects.neo_hookean[1]: a second material" "  neo_hookean: [{E: 500, nu: 0.49}, {E: 50, nu: 0.3}]\n$good_effects"
bad no_material     "effects: no material"               "$good_effects"
bad no_patch        "needs a Dirichlet support"          "$nh\n  gaussian_traction: {gamma: 0.2}"
bad sliding_region  "effects.dirichlet.components: a dataset's Dirichlet regions fix every component" "$nh\n$good_effects\n  dirichlet: {box: [-1, -1, 1, -0.9], components: [1]}"
bad two_patches     "effects.dirichlet_patch[1]: a dataset has at most one dirichlet_patch" "$nh\n  dirichlet_patch: [{radius: 0.5}, {radius: 0.3}]\n  gaussian_traction: {gamma: 0.2}"
bad spring_key      "effects.spring.stiffness"           "$nh\n$good_effects\n  spring: {stiffness: -1}"
bad patch_center    "effects.dirichlet_patch.center"     "$nh\n  dirichlet_patch: {radius: 0.5, center: [1, 0]}\n  gaussian_traction: {gamma: 0.2}"
bad only_fixed      "no load scaled by alpha"            "$nh\n  dirichlet_patch: {radius: 0.5}\n  body_force: {value: [0, -1], scale: fixed}"
bad scale_material  "effects.neo_hookean.scale"          "  neo_hookean: {E: 500, nu: 0.49, scale: fixed}\n$good_effects"
bad scale_word      "effects.body_force.scale"           "$nh\n$good_effects\n  body_force: {value: [0, -1], scale: half}"
bad count_list      "effects.gaussian_traction[0].count"  "$nh\n  dirichlet_patch: {radius: 0.5}\n  gaussian_traction: [{gamma: 0.2, count: 2}]"
bad count_kind      "effects.gaussian_traction.count"    "$nh\n  dirichlet_patch: {radius: 0.5}\n  gaussian_traction: {gamma: 0.2, count: {uniform: [1, 3]}}"
bad count_material  "effects.neo_hookean.count"          "  neo_hookean: {E: 500, nu: 0.49, count: 2}\n$good_effects"
bad empty_list      "effects.gaussian_traction"          "$nh\n  dirichlet_patch: {radius: 0.5}\n  gaussian_traction: []"
bad shorthand_mix   "material: a shorthand"              "$nh\n$good_effects" "material: {E: 400}\n"
printf 'geometry: {base: circle}\neffects:\n  neo_hookean: {E: {uniform: [1, 2]}, nu: 0.49}\n  dirichlet_patch: {center: [1, 0], radius: 0.5}\n  gaussian_traction: {center: [-1, 0], direction: [0, 1], gamma: 0.2}\nload: {target: 0.3}\n' > "$work/draw_scene.yaml"
msg=$("$bin" solve "$work/draw_scene.yaml" -o "$work/draw.h5" 2>&1 >/dev/null); code=$?
[ "$code" -eq 2 ] && grep -qF "effects.neo_hookean.E: must be a number here" <<<"$msg" && [ ! -e "$work/draw.h5" ] \
  && ok "solve: a distribution in a scene file: $msg" || fail "solve with a distribution: exit $code: $msg"
finish
