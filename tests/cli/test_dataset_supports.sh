#!/usr/bin/env bash
# A dataset with several Dirichlet supports (configs/examples/clamps2d.yaml: the drawn patch and
# two fixed regions; 2 shapes x 2 load cases): identical bit for bit on 1 and 2 ranks, to 1e-9
# in a solver group of 2 ranks; the stored Dirichlet facets are exactly those of the patch and
# of the regions, the mask covers their nodes, and no traction acts inside them.
. "$(dirname "$0")/lib.sh"
sed -E 's/^shapes: \{count: [0-9]+/shapes: {count: 2/; s/^loads: \{count: [0-9]+/loads: {count: 2/' \
    "$src/configs/examples/clamps2d.yaml" > "$work/clamps.yaml"
"$bin" -q generate "$work/clamps.yaml" --progress 0 -o "$work/np1" || fail "1-rank run"
mpiexec -n 2 "$bin" -q generate "$work/clamps.yaml" --progress 0 -o "$work/np2" || fail "2-rank run"
mpiexec -n 2 "$bin" -q generate "$work/clamps.yaml" --progress 0 --group-size 2 -o "$work/g2" || fail "group of 2"
compare "$work/np1" "$work/np2" >/dev/null && ok "1 rank == 2 ranks, bit for bit" || fail "1 rank != 2 ranks"
# (a group does not relax patches before the corrector's steps: the same equilibria by other paths)
compare "$work/np1" "$work/g2" --rtol 1e-7 --paths-differ >/dev/null && ok "1 rank == a group of 2 ranks, the same equilibria to 1e-7" || fail "1 rank != g2"
/usr/bin/python3 "$src/scripts/hypershape_data.py" check "$work/np1" >/dev/null && ok "hypershape_data.py check" || fail "check"
/usr/bin/python3 - "$work/np1" <<'PY' && ok "Dirichlet facets = patch + regions; mask on their nodes; no traction inside them" || fail "supports stored"
import sys
import h5py, numpy as np
import glob
n_region = 0
for path in sorted(glob.glob(sys.argv[1] + "/shards/*.h5")):
    with h5py.File(path) as h:
        for sid, g in h["shapes"].items():
            x, f = g["boundary/points"][:], g["boundary/facets"][:]
            pd, r = g.attrs["dirichlet_center"][:2], float(g.attrs["dirichlet_radius"])
            tol = 1e-9
            box = (x[:, 0] <= -0.85 + tol)
            ball = np.hypot(x[:, 0], x[:, 1] + 1.4) <= 0.5 + tol
            patch = np.hypot(x[:, 0] - pd[0], x[:, 1] - pd[1]) <= r + 1e-6
            want = np.flatnonzero(box[f].all(1) | ball[f].all(1) | patch[f].all(1))
            got = np.sort(g["dirichlet_facets"][:])
            assert np.array_equal(want, got), (sid, len(want), len(got))
            n_region += int((box[f].all(1) | ball[f].all(1)).sum())
            mask = g["dirichlet_mask"][:]
            assert mask[np.unique(f[got])].all(), sid
            # No traction inside a support (its end nodes, on a Neumann facet too, may carry one).
            inside = (mask == 1) & (g["neumann_mask"][:] == 0)
            assert inside.sum() > 0 and np.abs(g["loads/traction"][:][:, inside]).max() == 0.0, sid
assert n_region > 0
PY
finish
