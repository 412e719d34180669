#!/usr/bin/env bash
# The effects catalogue from the command line (configs/examples/catalogue2d.yaml, shrunk to
# 2 shapes x 2 load cases): a Saint Venant-Kirchhoff material with a log-normal modulus field,
# a Gaussian traction and a fixed pressure drawn per load case.
#  - identical bit for bit on 1 and 2 ranks; the channels traction, modulus (1 component, the
#    same in each load case of a shape, another field per shape) and pressure (1 component, the
#    drawn value at the Neumann nodes) stored; the torch Dataset serves them;
#  - `hypershape solve` on the disk with each new material and load converges; Cook's membrane
#    (configs/scenes/cook_membrane.yaml) at h = 2 near the literature's u_y(48, 60);
#  - the follower pressure's scene converges;
#  - bad keys stop before any work: exit code 2, the key named.
. "$(dirname "$0")/lib.sh"
export PYTHONPATH="$src/scripts${PYTHONPATH:+:$PYTHONPATH}"

sed -e 's/count: 4, h: 0.08/count: 2, h: 0.1/; s/count: 4, target/count: 2, target/; s/grid_size: 32/grid_size: 16/' \
    "$src/configs/examples/catalogue2d.yaml" > "$work/cat.yaml"
"$bin" -q generate "$work/cat.yaml" --progress 0 -o "$work/np1" || fail "1-rank run"
mpiexec -n 2 "$bin" -q generate "$work/cat.yaml" --progress 0 -o "$work/np2" || fail "2-rank run"
if compare "$work/np1" "$work/np2" >/dev/null; then ok "1 rank == 2 ranks, bit for bit"; else fail "1 rank != 2 ranks"; fi

/usr/bin/python3 - "$work/np1" <<'PY' && ok "channels traction, modulus, pressure stored and served" || fail "stored data"
import sys
import numpy as np
import hypershape_data as hd
import hypershape_torch as ht
ds = hd.open_dataset(sys.argv[1])
assert ds.channels == ["traction", "modulus", "pressure"], ds.channels
assert ds.channel_components == {"traction": 2, "modulus": 1, "pressure": 1}, ds.channel_components
fields = {}
for sid, lid in ds.keys():
    s = ds.sample(sid, lid)
    m, p = s.point_cloud["modulus"][:, 0], s.point_cloud["pressure"][:, 0]
    assert 0.2 < m.min() < 1 < m.max() < 5, (m.min(), m.max())      # cv 0.3 about 1
    assert np.allclose(p[s.neumann_mask], s.params["pressure/value"]) and np.all(p[~s.neumann_mask] == 0)
    assert 1.0 <= s.params["pressure/value"] <= 3.0
    if sid in fields:
        assert np.array_equal(fields[sid], m)                            # one field per shape
    fields[sid] = m
    assert s.grid["modulus"].shape == (16, 16, 1)
assert len(fields) == 2
a, b = fields.values()
assert len(a) != len(b) or not np.allclose(a, b)                        # another field per shape
g = ht.GridDataset(sys.argv[1], "train", normalize="channelwise")
assert g.x_channels == ["sdf", "dirichlet_distance", "traction_x", "traction_y", "modulus", "pressure"], g.x_channels
assert g[0]["x"].shape == (6, 16, 16)
PY

scene() {  # $1: the effects (YAML lines, 2 spaces in), $2: the load line
  printf 'geometry: {base: circle}\nmesh: {h: 0.1}\neffects:\n%s\n  dirichlet_patch: {center: [1.0, 0.0], radius: 0.5}\n%s\n' "$1" "$2"
}
traction='  gaussian_traction: {center: [-1.0, 0.0], direction: [0.0, 1.0], gamma: 0.2}'
for m in '  saint_venant_kirchhoff: {E: 500, nu: 0.4}' '  mooney_rivlin: {C1: 60, C2: 20, kappa: 800}' \
         '  mooney_rivlin: {C1: 60, C2: 20, D1: 0.0025}' '  linear_elastic: {E: 500, nu: 0.49}' \
         '  neo_hookean: {E: 500, nu: 0.4, E_cv: 0.5, E_length: 0.3, E_seed: 3}'; do
  scene "$m
$traction" "load: {target: 0.2}" > "$work/s.yaml"
  "$bin" -q solve "$work/s.yaml" -o "$work/s.h5" >/dev/null 2>&1 && ok "solve: $m" || fail "solve: $m"
done
scene "  neo_hookean: {E: 500, nu: 0.4}
  pressure: {value: 1.0, center: [-1.0, 0.0], radius: 0.8}
  uniform_traction: {value: [0.0, -1.0], box: [-1.0, -1.0, -0.5, 1.0], scale: fixed}" "load: {target: 0.1}" > "$work/s.yaml"
"$bin" -q solve "$work/s.yaml" -o "$work/s.h5" >/dev/null 2>&1 && ok "solve: pressure + uniform_traction" || fail "solve: loads"

# The follower pressure's scene (a cantilever, the pressure on its top face turning with it): LU
# solves, converged to max|u| = 2.
"$bin" -q solve "$src/configs/scenes/follower_pressure.yaml" -o "$work/f.h5" >/dev/null 2>&1 \
  && ok "solve: follower pressure (configs/scenes/follower_pressure.yaml)" || fail "solve: follower pressure"

# Cook's membrane (a polygon scene, a clamped edge, a shear traction on an edge) at h = 2, P2:
# u_y(48, 60) within 0.6% of the literature's 6.9083 (measured 6.8822, -0.38%).
sed 's/mesh: {h: 1.0, degree: 2}/mesh: {h: 2.0, degree: 2}/' "$src/configs/scenes/cook_membrane.yaml" > "$work/cook.yaml"
"$bin" -q solve "$work/cook.yaml" -o "$work/cook.h5" >/dev/null 2>&1 || fail "solve: Cook's membrane"
/usr/bin/python3 - "$work/cook.h5" <<'PY' && ok "Cook's membrane: u_y(48, 60) near 6.9083" || fail "Cook's membrane u_y"
import sys
import h5py
import numpy as np
with h5py.File(sys.argv[1], "r") as f:
    x, u = f["mesh/nodes"][()], f["fields/displacement"][()]
i = int(np.argmin(np.hypot(x[:, 0] - 48, x[:, 1] - 60)))
assert np.allclose(x[i], [48, 60]), x[i]
print("u_y(48, 60) =", u[i, 1])
assert abs(u[i, 1] / 6.9083 - 1) < 0.006, u[i, 1]
PY

bad() {  # $1: an effect line, $2: the key path the message must name
  scene "$1
$traction" "load: {target: 0.2}" > "$work/bad.yaml"
  out=$("$bin" -q solve "$work/bad.yaml" -o "$work/bad.h5" 2>&1); rc=$?
  if [ $rc -eq 2 ] && grep -q -- "$2" <<<"$out" && grep -q "bad.yaml" <<<"$out" && [ ! -e "$work/bad.h5" ]; then
    ok "rejected: $2"
  else
    fail "bad scene '$1' (rc $rc): $out"
  fi
}
bad '  mooney_rivlin: {C1: 60, C2: 20}' 'effects.mooney_rivlin.kappa'
bad '  mooney_rivlin: {C1: -1, C2: 20, kappa: 8}' 'effects.mooney_rivlin.C1'
bad '  saint_venant_kirchhoff: {E: 500, nu: 0.5}' 'effects.saint_venant_kirchhoff.nu'
bad '  linear_elastic: {E: 500, nu: 0.3, E_cv: 0.2}' 'effects.linear_elastic.E_length'
bad '  neo_hookean: {E: 500, nu: 0.3}
  pressure: {value: 1, box: [0, 0, 1]}' 'effects.pressure.box'
bad '  neo_hookean: {E: 500, nu: 0.3}
  dirichlet: {components: [0]}' 'effects.dirichlet.box'
bad '  neo_hookean: {E: 500, nu: 0.3}
  pressure: {value: 1, follower: yes}' 'effects.pressure.follower'
printf 'geometry: {polygon: [[0, 0], [1, 0]]}\nmesh: {h: 0.1}\neffects:\n  linear_elastic: {E: 1, nu: 0.3}\n  dirichlet: {box: [0, 0, 0, 1]}\nload: {alpha: 1}\n' > "$work/bad.yaml"
out=$("$bin" -q solve "$work/bad.yaml" -o "$work/bad.h5" 2>&1); rc=$?
[ $rc -eq 2 ] && grep -q "geometry.polygon" <<<"$out" && ok "rejected: geometry.polygon" || fail "bad polygon (rc $rc): $out"
finish
