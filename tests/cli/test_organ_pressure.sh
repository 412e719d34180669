#!/usr/bin/env bash
# The 3D example beyond the paper (configs/examples/organ_pressure3d.yaml, shrunk to 2 shapes x
# 2 load cases, 16^3 grids, one shape per shard): AugLiver-style organs, the drawn clamp patch,
# a Gaussian traction tuned to the target and a fixed dead pressure on the upper side drawn per
# load case.
#  - identical bit for bit on 1 and 2 ranks (each rank a shard);
#  - every load case converged; the channels are traction and pressure (docs/FORMAT.md): the
#    pressure channel is the drawn p (params/pressure/value, in [0.3, 1.0]) at the Neumann nodes
#    with z >= 0.2 and 0 at every other node, and on the grid p exactly at the points with
#    z >= 0.2; the stored scene names the pressure;
#  - a box of 4 numbers (2D) on the 3D organ: exit code 2 before any work, the key named.
# (The pressure's resultant on the organ surface: tests/physics/mpi_test_organ_pressure.cpp.)
. "$(dirname "$0")/lib.sh"
export PYTHONPATH="$src/scripts${PYTHONPATH:+:$PYTHONPATH}"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1

config="$src/configs/examples/organ_pressure3d.yaml"
sed -e 's/^shapes: {count: [0-9]*}/shapes: {count: 2}/; s/^loads: {count: [0-9]*,/loads: {count: 2,/' \
    -e 's/shard_size: 2/shard_size: 1/' "$config" > "$work/organ.yaml"
echo "representations: {grid_size: 16}" >> "$work/organ.yaml"
grep -q "count: 2}" "$work/organ.yaml" && grep -q "loads: {count: 2," "$work/organ.yaml" || fail "config not shrunk"
"$bin" -q generate "$work/organ.yaml" --progress 0 -o "$work/np1" || fail "1-rank run"
mpiexec -n 2 "$bin" -q generate "$work/organ.yaml" --progress 0 -o "$work/np2" || fail "2-rank run"
if compare "$work/np1" "$work/np2" >/dev/null; then ok "1 rank == 2 ranks, bit for bit"; else fail "1 rank != 2 ranks"; fi

/usr/bin/python3 - "$work/np1" <<'PY' && ok "pressure channel: p at the Neumann nodes and grid points with z >= 0.2" || fail "stored data"
import sys
import h5py
import numpy as np
import hypershape_data as hd
ds = hd.open_dataset(sys.argv[1])
assert ds.dim == 3 and ds.channels == ["traction", "pressure"], (ds.dim, ds.channels)
assert ds.channel_components == {"traction": 3, "pressure": 1}, ds.channel_components
x = np.linspace(-1, 1, 16)
grid_z = np.meshgrid(x, x, x, indexing="ij")[2]
in_box = grid_z >= 0.2 - 1e-9                                    # the plane z = 0.2 holds grid points (i = 9)
ps, n = set(), 0
for sid, lid in ds.keys():
    s = ds.sample(sid, lid)
    assert s.status == 1, s.reason
    p = float(s.params["pressure/value"])
    assert 0.3 <= p <= 1.0, p
    ps.add(p)
    z, pc = s.nodes[:, 2], s.point_cloud["pressure"][:, 0]
    assert abs(z - 0.2).min() > 1e-6                              # no node on the box's face
    inside = s.neumann_mask & (z > 0.2)
    assert inside.sum() > 20 and np.all(pc[inside] == p) and np.all(pc[~inside] == 0), (inside.sum(), p)
    g = s.grid["pressure"][..., 0]
    assert g.shape == (16, 16, 16) and np.array_equal(g == np.float32(p), in_box) and np.all(g[~in_box] == 0)
    n += 1
assert n == 4 and len(ps) == 4, (n, ps)                           # drawn per load case
with h5py.File(sorted(__import__("glob").glob(sys.argv[1] + "/shards/*.h5"))[0], "r") as f:
    scene = f["scene"][()].decode() if isinstance(f["scene"][()], bytes) else str(f["scene"][()])
assert "pressure" in scene and "box" in scene, scene
PY

# A 2D box on the 3D organ stops before any work, the key named.
sed 's/box: \[-3, -3, 0.2, 3, 3, 3\]/box: [-3, 0.2, 3, 3]/' "$work/organ.yaml" > "$work/bad.yaml"
out=$("$bin" -q generate "$work/bad.yaml" --progress 0 -o "$work/bad" 2>&1); code=$?
if [ "$code" = 2 ] && [[ $out == *"effects.pressure.box: must be a list of 6 numbers"* ]] && [ ! -e "$work/bad" ]; then
  ok "a 2D box on the organ: exit 2, effects.pressure.box named"
else fail "bad box: exit $code, $out"; fi
finish
