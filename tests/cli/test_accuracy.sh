#!/usr/bin/env bash
# Datasets asked for by accuracy (issue 19, config `accuracy: {rel_l2: B}`): a bad block is
# refused before any work, naming the key; a load case whose label misses a bound the config's
# own mesh cannot meet climbs the ladder (P1 -> P2 -> P2 on the mesh refined) until its estimate
# meets it, each label's level recorded (loads/accuracy_level), the shape stored on its finest
# label's level (attributes accuracy_*) with the coarser labels carried to that mesh exactly; a
# loose bound keeps level 0, whose arrays are those of the same config without the key; with
# `start: coarse` a re-solve starts from the level below's estimate and reaches the same labels.
# Needs HYPERSHAPE_BIN and HYPERSHAPE_SOURCE_DIR (set by CTest).
. "$(dirname "$0")/lib.sh"

base='preset: random2d_p1
name: acc
seed: 7
shapes: {count: 2, h: 0.1}
loads: {count: 3}
representations: {grid_size: 16}'

# Bad values: refused with the key named, nothing written.
refuse() {  # $1: accuracy block, $2: key the message must name
  printf '%s\naccuracy: %s\n' "$base" "$1" > "$work/bad.yaml"
  if "$bin" -q generate "$work/bad.yaml" --progress 0 -o "$work/bad" > "$work/bad.txt" 2>&1; then
    fail "accuracy: $1 accepted"
  elif ! grep -q "$2" "$work/bad.txt"; then
    cat "$work/bad.txt"; fail "accuracy: $1: message does not name $2"
  elif [ -e "$work/bad" ]; then
    fail "accuracy: $1: output written before the refusal"
  else
    ok "accuracy: $1 refused, naming $2"
  fi
}
refuse '{rel_l2: 0}' 'accuracy.rel_l2'
refuse '{rel_l2: 1.5}' 'accuracy.rel_l2'
refuse '{rel_l2: tight}' 'accuracy.rel_l2'
refuse '{rel_l2: 0.01, max_levle: 2}' 'accuracy.max_levle'
refuse '{max_level: 2}' 'accuracy.rel_l2'
refuse '{rel_l2: 0.01, max_level: 9}' 'accuracy.max_level'
refuse '{rel_l2: 0.01, start: coarsest}' 'accuracy.start'
refuse '{rel_l2: 0.01, resolve_newton_budget: 0}' 'accuracy.resolve_newton_budget'
refuse '{rel_l2: 0.01, resolve_retries: maybe}' 'accuracy.resolve_retries'

# shapes.py: every shape group of a dataset's shards, by id (the checks below import it).
cat > "$work/shapes.py" <<'PY'
import glob, h5py
def shapes(d):
    out = {}
    for f in sorted(glob.glob(f"{d}/shards/*.h5")):
        h = h5py.File(f)
        out.update({sid: g for sid, g in h["shapes"].items()})
    return out
PY

# check.py DIR BOUND MIN_LEVEL [MAX_LEVEL]: every label's level recorded, >= MIN_LEVEL, the shape
# stored on the finest; its estimate meets BOUND or is counted in accuracy_exceeding, allowed below
# MAX_LEVEL (default 2) only where not even MAX_LEVEL is predicted to meet BOUND (P1 -> P2 / 10,
# / 2 per refinement) or a higher level was tried and did no better; the report agrees.
cat > "$work/check.py" <<'PY'
import glob, h5py, json, sys
import numpy as np
d, bound, min_level = sys.argv[1], float(sys.argv[2]), int(sys.argv[3])
max_level = int(sys.argv[4]) if len(sys.argv) > 4 else 2
reduction = lambda lvl: (10 if lvl == 0 else 1) * 2 ** (max(0, max_level - 1) - max(0, lvl - 1))  # P1 ladder
levels, labels, meeting, exceeding = [], [0] * 4, 0, 0
for f in sorted(glob.glob(f"{d}/shards/*.h5")):
    with h5py.File(f) as h:
        for sid, g in h["shapes"].items():
            a = g.attrs
            lvl = int(a["accuracy_level"]); levels.append(lvl)
            st = g["loads/status"][...] == 1
            own, tried = g["loads/accuracy_level"][...][st], g["loads/accuracy_tried"][...][st]
            assert lvl == own.max() and (own >= min_level).all() and (tried >= own).all(), (sid, lvl, own, tried)
            for k in own: labels[k] += 1
            assert int(a["accuracy_degree"]) == (1 if lvl == 0 else 2), (sid, dict(a))
            n_cell_nodes = g["cells"].shape[1]
            assert n_cell_nodes == (3 if lvl == 0 else 6), (sid, n_cell_nodes)
            e = g["loads/error_estimate_rel_l2"][...][st]
            miss = (e < 0) | (e > bound)
            assert miss.sum() == int(a["accuracy_exceeding"]), (sid, e, dict(a))
            for x, k, t in zip(e[miss], own[miss], tried[miss]):  # a miss stays only where no level would cure it
                assert k == max_level or t > k or (x >= 0 and x / reduction(k) > bound), (sid, x, k, t)
            assert abs(float(a["accuracy_estimate_max"]) - e.max()) < 1e-12, (sid, e, dict(a))
            meeting += len(e) - miss.sum(); exceeding += miss.sum()
rep = json.load(open(glob.glob(f"{d}/reports/*.json")[0]))["accuracy"]
assert rep["shapes_at_level"][:3] == [levels.count(k) for k in range(3)], (rep, levels)
assert rep["load_cases_at_level"] == labels, (rep, labels)
assert rep["load_cases_meeting"] == meeting and rep["load_cases_exceeding"] == exceeding, (rep, meeting, exceeding)
assert 0 <= rep["load_cases_fell_back"] <= rep["load_cases_solved_again"], rep  # max_level <= 2: at most one per load case
print("levels", levels, "meeting", meeting, "exceeding", exceeding, "discarded", rep["discarded_load_cases"])
PY

# A bound P1 at h 0.1 misses (its estimates are 0.1-0.3): every shape moves to P2 or beyond.
printf '%s\naccuracy: {rel_l2: 0.05}\n' "$base" > "$work/tight.yaml"
"$bin" generate "$work/tight.yaml" --progress 0 -o "$work/tight" > "$work/tight.txt" 2>&1 || { cat "$work/tight.txt"; fail "generate (tight)"; }
/usr/bin/python3 "$work/check.py" "$work/tight" 0.05 1 && ok "rel_l2 0.05: every label above level 0, estimates meet the bound" \
  || fail "rel_l2 0.05"
mpiexec -n 2 "$bin" generate "$work/tight.yaml" --progress 0 -o "$work/tight_np2" > /dev/null 2>&1 || fail "2-rank run (tight)"
compare "$work/tight" "$work/tight_np2" > "$work/cmp.txt" && ok "2 ranks choose the same levels: the same dataset bit for bit" \
  || { head -20 "$work/cmp.txt"; fail "2 ranks differ from 1"; }
grep -q "accuracy rel_l2 <= 0.05" "$work/tight.txt" && ok "printed summary names the bound" || { cat "$work/tight.txt"; fail "summary line"; }

# From P2, one level up is the mesh refined (refine_shape: boundary and patch kept).
printf '%s\nmesh: {degree: 2}\naccuracy: {rel_l2: 0.02, max_level: 1}\n' "$base" > "$work/refine.yaml"
"$bin" -q generate "$work/refine.yaml" --progress 0 -o "$work/refine" > "$work/refine.txt" 2>&1 || { cat "$work/refine.txt"; fail "generate (refined)"; }
/usr/bin/python3 - "$work/refine" <<'PY' && ok "P2 + refinement: level 1 stores the refined mesh, masks on its boundary" || fail "refined level"
import glob, h5py, sys
import numpy as np
n1 = 0
for f in sorted(glob.glob(f"{sys.argv[1]}/shards/*.h5")):
    with h5py.File(f) as h:
        for sid, g in h["shapes"].items():
            a = g.attrs
            if int(a["accuracy_level"]) != 1: continue
            n1 += 1
            assert abs(a["accuracy_h"] - 0.05) < 1e-12, dict(a)
            x = g["nodes"][...]; c = g["cells"][...]
            # P2 on the refined mesh: the areas add up to the drawn polygon's (shoelace)
            p = x[c[:, :3]]
            area = 0.5 * np.abs((p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1]) - (p[:, 2, 0] - p[:, 0, 0]) * (p[:, 1, 1] - p[:, 0, 1])).sum()
            assert abs(area - a["measure"]) < 1e-9 * max(1, a["measure"]), (area, a["measure"])
            dm, nm = g["dirichlet_mask"][...], g["neumann_mask"][...]
            assert dm.sum() > 0 and nm.sum() > 0 and (g["loads/status"][...] == 1).any()
assert n1 > 0, "no shape at level 1"
PY

# With `start: coarse` a re-solve on the mesh below refined once starts from the state the label's
# estimate reached there: here the same labels as from rest (the default) to the solver's
# tolerance, for fewer factorisations; each such label's reason says where it started.
printf '%s\nmesh: {degree: 2}\naccuracy: {rel_l2: 0.02, max_level: 1, start: coarse}\n' "$base" > "$work/refine_coarse.yaml"
"$bin" -q generate "$work/refine_coarse.yaml" --progress 0 -o "$work/refine_coarse" > /dev/null 2>&1 || fail "generate (refined, start: coarse)"
PYTHONPATH="$work" /usr/bin/python3 - "$work/refine_coarse" "$work/refine" <<'PY' && ok "start: coarse: the labels of start: rest (alpha to 1e-6, u to 1e-5 of max|u|), fewer factorisations" \
  || fail "start: coarse against start: rest"
import glob, h5py, json, sys
from shapes import shapes
def counts(d):
    return json.load(open(glob.glob(f"{d}/reports/*.json")[0]))["solver"]["numeric_factorizations"]
coarse, rest = shapes(sys.argv[1]), shapes(sys.argv[2])
warm = 0
for sid, g in coarse.items():
    r = rest[sid]
    lv, st = g["loads/accuracy_level"][...], g["loads/status"][...]
    assert (lv == r["loads/accuracy_level"][...]).all() and (st == r["loads/status"][...]).all(), sid
    reasons = [x.decode() if isinstance(x, bytes) else x for x in g["loads/reason"][...]]
    for L in range(len(lv)):
        if not st[L] or lv[L] == 0: continue
        warm += reasons[L].startswith("from the level-0 estimate")
        a, b = g["loads/alpha"][L], r["loads/alpha"][L]
        assert abs(a - b) <= 1e-6 * abs(b), (sid, L, a, b)
        u, v = g["loads/displacement"][L], r["loads/displacement"][L]
        assert abs(u - v).max() <= 1e-5 * abs(v).max(), (sid, L, abs(u - v).max())
assert warm > 0, "no label started from the level below's estimate"
assert counts(sys.argv[1]) < counts(sys.argv[2]), (counts(sys.argv[1]), counts(sys.argv[2]))
print("labels started from level 0:", warm, "factorisations", counts(sys.argv[1]), "against", counts(sys.argv[2]))
PY
mpiexec -n 2 "$bin" -q generate "$work/refine_coarse.yaml" --progress 0 -o "$work/refine_np2" > /dev/null 2>&1 || fail "2-rank run (refined)"
compare "$work/refine_coarse" "$work/refine_np2" > "$work/cmp.txt" && ok "labels started from the estimate's state: 2 ranks make the same dataset bit for bit" \
  || { head -20 "$work/cmp.txt"; fail "2 ranks differ from 1 (refined)"; }

# A loose bound keeps level 0: the arrays are those of the config without the key (estimates on).
printf '%s\naccuracy: {rel_l2: 0.9}\n' "$base" > "$work/loose.yaml"
printf '%s\n' "$base" | sed 's/grid_size: 16}/grid_size: 16, error_estimate: true}/' > "$work/plain.yaml"
"$bin" -q generate "$work/loose.yaml" --progress 0 -o "$work/loose" > /dev/null 2>&1 || fail "generate (loose)"
"$bin" -q generate "$work/plain.yaml" --progress 0 -o "$work/plain" > /dev/null 2>&1 || fail "generate (plain)"
/usr/bin/python3 "$work/check.py" "$work/loose" 0.9 0 > /dev/null || fail "rel_l2 0.9: check"
cat > "$work/same.py" <<'PY'
import glob, h5py, sys
import numpy as np
def arrays(d):
    out = {}
    for f in sorted(glob.glob(f"{d}/shards/*.h5")):
        with h5py.File(f) as h:
            def visit(name, obj):
                if isinstance(obj, h5py.Dataset) and name.startswith("shapes/"):
                    if "/loads/accuracy_" in name: assert (obj[...] == 0).all(), name  # no label climbed
                    else: out[name] = obj[...]
            h.visititems(visit)
            for sid, g in h["shapes"].items():
                assert g.attrs.get("accuracy_level", 0) == 0
    return out
a, b = arrays(sys.argv[1]), arrays(sys.argv[2])
assert a.keys() == b.keys() and len(a) > 10, (sorted(set(a) ^ set(b)))
for k in a:
    assert a[k].shape == b[k].shape and (a[k] == b[k]).all(), k
PY
/usr/bin/python3 "$work/same.py" "$work/loose" "$work/plain" && ok "rel_l2 0.9: level 0 everywhere, arrays identical to the config without accuracy:" \
  || fail "loose bound differs from no bound"

# A bound no level can be predicted to meet (P1 at h 0.1 estimates 0.1-0.3; P2 on the same mesh,
# the last level, is predicted 10x lower: above 0.003 still) moves no shape: level 0 is kept,
# every load case above the bound counted, as the same config without the key would store it.
printf '%s\naccuracy: {rel_l2: 0.003, max_level: 1}\n' "$base" > "$work/hopeless.yaml"
"$bin" -q generate "$work/hopeless.yaml" --progress 0 -o "$work/hopeless" > /dev/null 2>&1 || fail "generate (hopeless)"
/usr/bin/python3 "$work/check.py" "$work/hopeless" 0.003 0 1 > "$work/hopeless.txt" \
  && grep -q "levels \[0, 0\] meeting 0 exceeding 6 discarded 0" "$work/hopeless.txt" \
  && /usr/bin/python3 "$work/same.py" "$work/hopeless" "$work/plain" \
  && ok "rel_l2 0.003 with max_level 1: no shape climbs for labels no level would cure, all 6 counted above" \
  || { cat "$work/hopeless.txt"; fail "hopeless bound"; }

# A bound some labels of a shape meet at level 0 and others not (P1 at h 0.1 estimates 0.07-0.28
# here): only those climb; the shape is stored at level 1 (P2) and the labels kept at level 0 are
# the config-without-the-key's, carried to the P2 mesh: equal at the vertices (to round-off), the mean of their
# ends at the edge midpoints; alpha, status, iterations and estimates the same.
printf '%s\naccuracy: {rel_l2: 0.16, max_level: 1}\n' "$base" > "$work/mixed.yaml"
"$bin" -q generate "$work/mixed.yaml" --progress 0 -o "$work/mixed" > /dev/null 2>&1 || fail "generate (mixed)"
/usr/bin/python3 "$work/check.py" "$work/mixed" 0.16 0 1 > /dev/null || fail "rel_l2 0.16: check"
mpiexec -n 2 "$bin" -q generate "$work/mixed.yaml" --progress 0 -o "$work/mixed_np2" > /dev/null 2>&1 || fail "2-rank run (mixed)"
compare "$work/mixed" "$work/mixed_np2" > "$work/cmp.txt" && ok "labels of two levels in a shape: 2 ranks make the same dataset bit for bit" \
  || { head -20 "$work/cmp.txt"; fail "2 ranks differ from 1 (mixed)"; }
PYTHONPATH="$work" /usr/bin/python3 - "$work/mixed" "$work/plain" <<'PY' && ok "rel_l2 0.16: only the labels above it climb; those kept at level 0 carried to the P2 mesh exactly" \
  || fail "per-load-case levels"
import glob, h5py, sys
import numpy as np
from shapes import shapes
mixed, plain = shapes(sys.argv[1]), shapes(sys.argv[2])
carried = 0
for sid, g in mixed.items():
    p = plain[sid]
    own = g["loads/accuracy_level"][...]
    climbed = own > 0
    assert (climbed == (p["loads/error_estimate_rel_l2"][...] > 0.16)).all(), (sid, own)
    if int(g.attrs["accuracy_level"]) == 0: continue
    x, c, u = g["nodes"][...], g["cells"][...], g["loads/displacement"][...]
    nv = p["nodes"].shape[0]
    assert np.array_equal(x[:nv], p["nodes"][...]), sid  # P2 on the same mesh: its vertices first
    for L in np.flatnonzero(~climbed):
        carried += 1
        assert np.abs(u[L, :nv] - p["loads/displacement"][L]).max() < 1e-14, (sid, L)  # round-off of the interpolation
        for (a, b, m) in [(0, 1, 3), (1, 2, 4), (2, 0, 5)]:
            assert np.allclose(u[L, c[:, m]], 0.5 * (u[L, c[:, a]] + u[L, c[:, b]]), rtol=0, atol=1e-14), (sid, L)
        for key in ["status", "alpha", "newton_iterations", "error_estimate_rel_l2", "min_det_f", "traction_normaliser"]:
            assert g[f"loads/{key}"][L] == p[f"loads/{key}"][L], (sid, L, key)
        assert np.array_equal(g["loads/traction"][L, :nv], p["loads/traction"][L]), (sid, L)
    for L in np.flatnonzero(climbed):
        assert g["loads/error_estimate_rel_l2"][L] < p["loads/error_estimate_rel_l2"][L], (sid, L)
assert carried > 0, "no shape mixes levels"
print("labels carried from level 0:", carried)
PY
# The same bound with a re-solve budget of one Newton iteration: every re-solve fails within it and
# keeps the label it had (the log says so, with its cost), so the labels are level 0's, the arrays
# those of the config without the key; only loads/accuracy_tried records the climbs tried.
printf '%s\naccuracy: {rel_l2: 0.16, max_level: 1, resolve_newton_budget: 1}\n' "$base" > "$work/capped.yaml"
"$bin" generate "$work/capped.yaml" --progress 0 -o "$work/capped" > "$work/capped.txt" 2>&1 || fail "generate (capped)"
PYTHONPATH="$work" /usr/bin/python3 - "$work/capped" "$work/plain" <<'PY' && grep -q "keeps its level-0 label .*at level 1 it failed .*(1 Newton iterations" "$work/capped.txt" \
  && ok "resolve_newton_budget 1: every re-solve fails within it, the labels stay level 0's (arrays as without the key)" \
  || { grep "keeps its" "$work/capped.txt" | head -3; fail "resolve_newton_budget"; }
import sys
import numpy as np
from shapes import shapes
capped, plain = shapes(sys.argv[1]), shapes(sys.argv[2])
def arrays(h):  # every array of a shape group but the ladder's own
    out = {}
    h.visititems(lambda n, o: out.__setitem__(n, o[...]) if hasattr(o, "shape") and "accuracy_" not in n else None)
    return out
tried = 0
for sid, g in capped.items():
    p = plain[sid]
    assert int(g.attrs["accuracy_level"]) == 0, sid
    assert (g["loads/accuracy_level"][...] == 0).all(), sid
    t = g["loads/accuracy_tried"][...]
    assert (((t == 1) == (p["loads/error_estimate_rel_l2"][...] > 0.16))).all(), (sid, t)
    tried += int(t.sum())
    a, b = arrays(g), arrays(p)
    assert a.keys() == b.keys(), sorted(set(a) ^ set(b))
    for k in a: assert a[k].shape == b[k].shape and (a[k] == b[k]).all(), (sid, k)
assert tried > 0, "no label tried to climb"
PY
# With resolve_retries: false a re-solve makes one try: the budget-1 re-solves above went on to the
# solver's P1 start ("P1 on the same mesh"); these fail without it, keeping the same labels.
printf '%s\naccuracy: {rel_l2: 0.16, max_level: 1, resolve_newton_budget: 1, resolve_retries: false}\n' "$base" > "$work/once.yaml"
"$bin" generate "$work/once.yaml" --progress 0 -o "$work/once" > "$work/once.txt" 2>&1 || fail "generate (once)"
n_p1=$(grep -c "keeps its level-0 label .*P1 on the same mesh" "$work/capped.txt")
n_once=$(grep -c "keeps its level-0 label .*at level 1 it failed (Newton budget of 1 iterations spent) (1 Newton" "$work/once.txt")
if [ "$n_p1" -gt 0 ] && [ "$n_once" -eq "$(grep -c "keeps its" "$work/capped.txt")" ] && ! grep -q "P1 on the same mesh\|from rest without" "$work/once.txt" &&
   PYTHONPATH="$work" /usr/bin/python3 - "$work/once" "$work/capped" <<'PY'
import sys
from shapes import shapes
once, capped = shapes(sys.argv[1]), shapes(sys.argv[2])
for sid, g in once.items():
    c = capped[sid]
    for k in ("status", "alpha", "displacement", "error_estimate_rel_l2", "accuracy_level", "accuracy_tried"):
        assert (g[f"loads/{k}"][...] == c[f"loads/{k}"][...]).all(), (sid, k)
PY
then ok "resolve_retries false: each failed re-solve made one try ($n_once; with retries $n_p1 went on to the P1 start), the same labels"
else grep "keeps its" "$work/once.txt" | head -3; fail "resolve_retries"; fi
PYTHONPATH="$src/scripts" /usr/bin/python3 - "$work/mixed" <<'PY' && ok "hypershape_data: each sample's accuracy_level, and the summary's labels per level" \
  || fail "hypershape_data accuracy_level"
import io, sys
import numpy as np
import hypershape_data as hd
ds = hd.open_dataset(sys.argv[1])
levels = [s.accuracy_level for s in (ds.sample(k, l) for k in ds.shape_ids() for l in range(ds.n_loads)) if s.status]
assert sorted(set(levels)) == [0, 1], levels
out = io.StringIO(); hd.summary(sys.argv[1], out)
assert f"labels per accuracy level (asked for by accuracy): 0: {levels.count(0)}, 1: {levels.count(1)}" in out.getvalue(), out.getvalue()
PY
finish
