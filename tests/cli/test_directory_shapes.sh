#!/usr/bin/env bash
# A directory family (`base: directory`, the Liver / OneLiver presets): one shape per surface
# file of base_dir, taken in file-name order, with no deformation.
#  - `hypershape generate` of 2 shapes x 2 load cases from a temporary directory of 2 surfaces
#    (plus files that must be ignored): the shard holds 2 shapes, records each shape's file
#    name, shape 0 and 1 have different meshes, every load case converged, dataset.yaml lists
#    the files;
#  - `hypershape shapes` on 2 ranks draws the same shapes (the file name travels between ranks).
# The presets (liver, one_liver) are checked in tests/config/test_presets.cpp.
# Bad directory configs are in test_generate.sh and test_shapes.sh. Needs HYPERSHAPE_BIN and
# HYPERSHAPE_SOURCE_DIR (set by CTest).
. "$(dirname "$0")/lib.sh"

# Two surfaces whose names sort against the shipped order (liver_001 becomes shape 0), one with
# an upper-case extension; a text file, a hidden broken surface and a directory named like a
# surface must all be ignored.
mkdir -p "$work/livers/sub.stl"
cp "$src/configs/surfaces/livers/liver_001.stl" "$work/livers/a_liver.stl"
cp "$src/configs/surfaces/livers/liver_000.stl" "$work/livers/b_liver.STL"
echo "not a surface" > "$work/livers/notes.txt"
printf 'solid x\nendsolid x\n' > "$work/livers/.hidden.stl"
cat > "$work/livers.yaml" <<'YAML'
preset: liver
name: livers_cli
seed: 11
shapes: {base_dir: livers, h: 0.2}   # relative to this file; count: the 2 files
loads: {count: 2}
representations: {grid_size: 8}
output: {shard_size: 2}
YAML

t0=$(date +%s)
if "$bin" -q generate "$work/livers.yaml" --progress 0 -o "$work/out"; then
  ok "generate: 2 surfaces x 2 load cases in $(( $(date +%s) - t0 )) s"
else
  fail "generate exited non-zero"
fi
/usr/bin/python3 - "$work/out" <<'PY' && ok "shard: 2 shapes, file names recorded, different meshes, all converged" || fail "shard content"
import glob, json, sys, h5py, numpy as np
d = sys.argv[1]
shards = sorted(glob.glob(f"{d}/shards/*.h5"))
assert len(shards) == 1, shards
with h5py.File(shards[0]) as h:
    assert h.attrs["n_shapes"] == 2 and h.attrs["dim"] == 3, dict(h.attrs)
    ids = sorted(h["shapes"])
    assert ids == ["000000", "000001"], ids
    g0, g1 = h["shapes/000000"], h["shapes/000001"]
    names = [g.attrs["source_file"] for g in (g0, g1)]
    names = [n.decode() if isinstance(n, bytes) else n for n in names]
    assert names == ["a_liver.stl", "b_liver.STL"], names
    for g in (g0, g1):
        assert g.attrs["status"] in (b"ok", "ok"), g.attrs["status"]
        st = g["loads/status"][()]
        assert st.shape == (2,) and st.all(), f"not converged: {st}, {list(g['loads/reason'][()])}"
        assert np.isfinite(g["loads/displacement"][()]).all()
    n0, n1 = g0["nodes"][()], g1["nodes"][()]
    assert n0.shape != n1.shape or not np.allclose(n0, n1), "shape 0 and 1 have the same mesh"
    # No deformation: shape 0 is its own file remeshed, the metrics' reference (the first file).
    h0, h1 = g0.attrs["hausdorff_to_base"], g1.attrs["hausdorff_to_base"]
    assert h0 < 0.1 < h1, (h0, h1)
m = json.load(open(f"{d}/manifest.json"))
assert m["complete"] and m["n_shapes"] == 2 and m["totals"]["load_cases_converged"] == 4, m["totals"]
text = open(f"{d}/dataset.yaml").read()
assert "0: a_liver.stl" in text and "1: b_liver.STL" in text and "notes" not in text, text
print(f"source files {names}; Hausdorff to the first file {h0:.3f}, {h1:.3f}; "
      f"{len(n0)} and {len(n1)} nodes")
PY

# The same shapes drawn on 2 ranks by `hypershape shapes` (shape 1 is made on rank 1 and
# gathered on rank 0 with its file name).
if mpiexec -n 2 --oversubscribe "$bin" -q shapes "$work/livers.yaml" -o "$work/shapes.h5"; then
  /usr/bin/python3 - "$work/shapes.h5" "$work/out" <<'PY' && ok "shapes on 2 ranks: same meshes and file names" || fail "shapes on 2 ranks"
import glob, sys, h5py, numpy as np
with h5py.File(sys.argv[1]) as s, h5py.File(glob.glob(f"{sys.argv[2]}/shards/*.h5")[0]) as h:
    for sid, name in [("000000", "a_liver.stl"), ("000001", "b_liver.STL")]:
        a, b = s["shapes"][sid], h["shapes"][sid]
        got = a.attrs["source_file"]
        assert (got.decode() if isinstance(got, bytes) else got) == name, got
        assert np.array_equal(a["mesh/nodes"][()], b["mesh/nodes"][()]), f"shape {sid}: mesh differs"
PY
else
  fail "shapes on 2 ranks exited non-zero"
fi

finish
