#!/usr/bin/env bash
# `hypershape generate`:
#  - the same dataset on 1, 2 and 3 ranks and as a 3-task array merged by `hypershape index`,
#    bit for bit, and with a solver group of 2 ranks to round-off (every array compared,
#    tests/cli/compare_datasets.py; without local relaxation, which a group does not do: with
#    it, the same equilibria to 1e-7), in 2D and for one 3D shape as the 3D presets solve it;
#  - kill -9 mid-run, then the same command: equal to the uninterrupted run, no temporary file;
#  - a load case forced to fail is recorded (status 0, reason) and nothing stored is NaN;
#  - bad configs and options stop before any work: message naming the key, non-zero exit,
#    nothing written (also a directory family's base_dir: missing, not a directory, no surface
#    file, a broken one, too few files for count, on the wrong base, in 2D).
# Needs HYPERSHAPE_BIN and HYPERSHAPE_SOURCE_DIR (set by CTest).
. "$(dirname "$0")/lib.sh"

cat > "$work/tiny.yaml" <<'YAML'
preset: random2d
name: tiny
seed: 7
shapes: {count: 5, h: 0.1}
loads: {count: 3}
representations: {grid_size: 16}
output: {shard_size: 2}
YAML
gen() { "$bin" -q generate "$work/tiny.yaml" --progress 0 "$@"; }

# ---- rank, group and task independence -------------------------------------------------------
gen -o "$work/np1" || fail "1-rank run"
mpiexec -n 2 "$bin" -q generate "$work/tiny.yaml" --progress 0 -o "$work/np2" || fail "2-rank run"
mpiexec -n 3 --oversubscribe "$bin" -q generate "$work/tiny.yaml" --progress 0 -o "$work/np3" || fail "3-rank run"
mpiexec -n 2 "$bin" -q generate "$work/tiny.yaml" --progress 0 --group-size 2 -o "$work/g2" || fail "group of 2"
for t in 0 1 2; do
  SLURM_ARRAY_TASK_ID=$((t + 1)) SLURM_ARRAY_TASK_MIN=1 SLURM_ARRAY_TASK_COUNT=3 gen -o "$work/array" || fail "task $t"
done
"$bin" -q index "$work/array" || fail "index of the array"
for d in np2 np3 array; do
  if compare "$work/np1" "$work/$d"; then ok "1 rank == $d, bit for bit"; else fail "1 rank != $d"; fi
done
# A group of 2 ranks solves each shape on a METIS partition: sums run in another order, so the
# values agree to round-off (measured: 5e-16 in u, 1e-13 in alpha), not bit for bit; so with
# local relaxation off, where both take the same paths (every array, the path counters too), on
# the mesh as drawn (mesh.rim 0: on the preset's graded ends, cells of 0.00375, round-off moved
# the path counters on 4 of the 5 shapes, not the equilibria):
sed 's/^output:/solver: {local_relaxation: false}\nmesh: {rim: 0}\noutput:/' "$work/tiny.yaml" > "$work/tiny_plain.yaml"
"$bin" -q generate "$work/tiny_plain.yaml" --progress 0 -o "$work/np1_plain" || fail "1-rank run, no relaxation"
mpiexec -n 2 "$bin" -q generate "$work/tiny_plain.yaml" --progress 0 --group-size 2 -o "$work/g2_plain" || fail "group of 2, no relaxation"
if compare "$work/np1_plain" "$work/g2_plain" --rtol 1e-9; then ok "no relaxation: 1 rank == groups of 2 ranks, to 1e-9"; else fail "no relaxation: 1 rank != g2"; fi
# By default one rank relaxes patches before the corrector's steps and a group does not
# (SolverOptions::local_relaxation): other paths to the same equilibria (measured: 2.2e-10).
if compare "$work/np1" "$work/g2" --rtol 1e-7 --paths-differ; then ok "1 rank == groups of 2 ranks: the same equilibria to 1e-7"; else fail "1 rank != g2"; fi
# 3D as the presets solve it: P2 on the surface remeshed at mesh.h 0.3 (one shape, 2 load cases;
# about 15 s), 1 rank against a solver group of 2 (measured: identical to 1e-12).
printf 'preset: random3d\nname: tiny3d\nseed: 7\nshapes: {count: 1}\nloads: {count: 2}\nrepresentations: {grid_size: 8}\n' > "$work/tiny3d.yaml"
"$bin" -q generate "$work/tiny3d.yaml" --progress 0 -o "$work/np1_3d" || fail "3D, 1 rank"
mpiexec -n 2 "$bin" -q generate "$work/tiny3d.yaml" --progress 0 --group-size 2 -o "$work/g2_3d" || fail "3D, group of 2"
if compare "$work/np1_3d" "$work/g2_3d" --rtol 1e-7 --paths-differ; then ok "3D P2 on mesh.h 0.3: 1 rank == a group of 2, the same equilibria to 1e-7"; else fail "3D: 1 rank != g2"; fi
# The multigrid path (solver.linear gamg: CG + GAMG, the LOBPCG stability check) on a group of 2
# ranks: the same labels as the direct solver on 1 rank, to the solver's tolerance (GAMG's
# aggregates are made per rank, so the Krylov iterates, not the equilibrium, depend on the group).
sed 's/^name: tiny3d$/name: tiny3d_amg\nsolver: {linear: gamg}/' "$work/tiny3d.yaml" > "$work/tiny3d_amg.yaml"
mpiexec -n 2 "$bin" -q generate "$work/tiny3d_amg.yaml" --progress 0 --group-size 2 -o "$work/g2_3d_amg" || fail "3D gamg, group of 2"
/usr/bin/python3 - "$work/np1_3d" "$work/g2_3d_amg" <<'PY' && ok "3D: gamg on a group of 2 == direct on 1 rank, u and alpha to 1e-7" || fail "3D: gamg g2 != direct np1"
import h5py, numpy as np, sys
a, b = (h5py.File(f"{d}/shards/shard-000000.h5")["shapes/000000"] for d in sys.argv[1:])
assert a["loads/status"][:].tolist() == b["loads/status"][:].tolist() == [1, 1]
for k in ("loads/alpha", "loads/displacement"):
    x, y = a[k][()], b[k][()]
    assert np.abs(x - y).max() <= 1e-7 * np.abs(x).max(), (k, np.abs(x - y).max())
PY
/usr/bin/python3 - "$work/np1_3d" <<'PY' && ok "3D: P2 cells on the coarse surface, both load cases converged" || fail "3D dataset"
import h5py, sys
g = h5py.File(f"{sys.argv[1]}/shards/shard-000000.h5")["shapes/000000"]
assert g["cells"].shape[1] == 10, g["cells"].shape             # P2 tetrahedra
assert g["boundary/facets"].shape[0] < 1000, g["boundary/facets"].shape  # ~300 at 0.3, ~3000 at 0.1
assert g["loads/status"][:].tolist() == [1, 1], g["loads/reason"][:]
PY
/usr/bin/python3 - "$work/np1" <<'PY' && ok "manifest, splits, stats, xdmf present" || fail "dataset files"
import json, os, sys
d = sys.argv[1]
m = json.load(open(f"{d}/manifest.json"))
assert m["complete"] and m["n_shapes"] == 5 and len(m["shards"]) == 3, m
s = json.load(open(f"{d}/splits.json"))
ids = s["train"] + s["val"] + s["test"]
assert len(ids) == len(set(ids)), "a shape in two splits"
assert sorted(ids) == sorted(set(range(5)) - set(m["failed_shapes"])), "splits do not cover the good shapes"
st = json.load(open(f"{d}/stats.json"))
assert "displacement" in st["fields"] and len(st["fields"]["displacement"]["mean"]) == 2
assert all(os.path.exists(f"{d}/xdmf/shard-{k:06d}.xdmf") for k in range(3))
PY

# ---- kill -9 and resume -----------------------------------------------------------------------
sed -e 's/count: 5/count: 12/; s/shard_size: 2/shard_size: 3/' "$work/tiny.yaml" > "$work/resume.yaml"
"$bin" -q generate "$work/resume.yaml" --progress 0 -o "$work/whole" || fail "uninterrupted run"
"$bin" -q generate "$work/resume.yaml" --progress 0 -o "$work/killed" &
pid=$!
for _ in $(seq 1 600); do  # kill once the first shard exists (mid-run)
  ls "$work/killed/shards/"*.h5 >/dev/null 2>&1 && break
  sleep 0.05
done
kill -9 "$pid" 2>/dev/null; wait "$pid" 2>/dev/null
n_before=$(ls "$work/killed/shards/"*.h5 2>/dev/null | wc -l)
if [ -e "$work/killed/manifest.json" ]; then fail "the killed run finished before the kill"; fi
"$bin" -q generate "$work/resume.yaml" --progress 0 -o "$work/killed" || fail "resumed run"
leftover=$(find "$work/killed" -name '*.tmp*' | wc -l)
if compare "$work/whole" "$work/killed" && [ "$leftover" -eq 0 ]; then
  ok "killed after $n_before of 4 shards, resumed: identical to the uninterrupted run, no temporary file"
else
  fail "resume: differs or $leftover temporary files left"
fi

# ---- a failing load case is data ------------------------------------------------------------
printf 'solver: {max_newton: 1, max_increments: 2}\n' | cat "$work/tiny.yaml" - |
  sed -e 's/count: 5/count: 2/' > "$work/failing.yaml"
"$bin" -q generate "$work/failing.yaml" --progress 0 -o "$work/failing" || fail "run with failures exits non-zero"
/usr/bin/python3 - "$work/failing" <<'PY' && ok "failed load cases recorded, no NaN" || fail "failure recording"
import glob, sys, h5py, numpy as np, json
d = sys.argv[1]
n_failed = 0
for f in glob.glob(f"{d}/shards/*.h5"):
    with h5py.File(f) as h:
        def visit(name, obj):
            if isinstance(obj, h5py.Dataset) and obj.dtype.kind == "f":
                assert np.isfinite(obj[()]).all(), f"{f}:{name} has NaN/Inf"
        h.visititems(visit)
        for sid, g in h["shapes"].items():
            st = g["loads/status"][()]
            reasons = [r.decode() if isinstance(r, bytes) else r for r in g["loads/reason"][()]]
            for s, r, u in zip(st, reasons, g["loads/displacement"][()]):
                if s == 0:
                    n_failed += 1
                    assert r and r != "target reached", f"shape {sid}: failed without a reason"
                    assert not u.any(), "a failed load case stored a displacement"
m = json.load(open(f"{d}/manifest.json"))
assert n_failed > 0 and m["totals"]["load_cases_failed"] == n_failed, (n_failed, m["totals"])
print(f"{n_failed} failed load cases, each with its reason")
PY

# ---- bad input --------------------------------------------------------------------------------
# expect NAME SED-EXPRESSION KEY-TEXT [EXTRA OPTIONS...]
expect() {
  local name=$1 expr=$2 key=$3; shift 3
  local cfg="$work/bad_$name.yaml" out=${OUT:-"$work/out_$name"}
  sed -e "$expr" "$work/tiny.yaml" > "$cfg"
  local msg code
  msg=$("$bin" generate "$cfg" --progress 0 -o "$out" "$@" 2>&1 >/dev/null); code=$?
  if [ "$code" -eq 0 ]; then fail "$name: exit 0"; return; fi
  if ! grep -qF -- "$key" <<<"$msg"; then fail "$name: message does not name '$key': $msg"; return; fi
  if [ -z "${OUT:-}" ] && [ -e "$out" ]; then fail "$name: left output behind"; return; fi
  ok "$name: $msg"
}
expect unknown_key     's/^seed: 7/seed: 7\ncolour: red/'                 "colour"
expect unknown_loads   's/loads: {count: 3}/loads: {count: 3, width: 2}/'  "loads.width"
expect loads_zero      's/loads: {count: 3}/loads: {count: 0}/'            "loads.count"
expect loads_type      's/loads: {count: 3}/loads: {count: many}/'         "loads.count"
expect target_order    's/loads: {count: 3}/loads: {target: [0.5, 0.1]}/'  "loads.target"
expect gamma_range     's/loads: {count: 3}/loads: {gamma: -1}/'           "loads.gamma"
expect nu_range        's/^seed: 7/seed: 7\nmaterial: {nu: 0.5}/'          "material.nu"
expect E_type          's/^seed: 7/seed: 7\nmaterial: {E: soft}/'          "material.E"
expect degree          's/^seed: 7/seed: 7\nmesh: {degree: 3}/'            "mesh.degree"
expect mesh_h_2d       's/^seed: 7/seed: 7\nmesh: {h: 0.2}/'               "mesh.h: only for 3D shapes"
expect mesh_h_fine     's/preset: random2d/preset: random3d/; s/^seed: 7/seed: 7\nmesh: {h: 0.05}/' "mesh.h: must be in [shapes.h = 0.1, 0.5]"
expect grid_size       's/grid_size: 16/grid_size: 100000/'                "representations.grid_size"
expect grid_flag       's/grid_size: 16/grid: maybe/'                      "representations.grid"
expect split_sum       's/^seed: 7/seed: 7\nsplit: {train: 0.9, val: 0.2, test: 0.1}/' "split"
expect shard_size      's/shard_size: 2/shard_size: 0/'                    "output.shard_size"
expect preset          's/preset: random2d/preset: random9d/'              "preset"
expect solver          's/^seed: 7/seed: 7\nsolver: {rtol: 2}/'             "solver.rtol"
expect control         's/^seed: 7/seed: 7\nsolver: {control: arclength}/' "solver.control"
expect budget          's/^seed: 7/seed: 7\nsolver: {newton_budget: 0}/'   "solver.newton_budget"
expect switches        's/^seed: 7/seed: 7\nsolver: {branch_switches: -1}/' "solver.branch_switches"
expect petsc           's/^seed: 7/seed: 7\npetsc: {pc_type: [lu]}/'       "petsc.pc_type"
expect shapes_h        's/h: 0.1/h: -1/'                                   "shapes.h"
expect surface_missing 's/preset: random2d/preset: random3d/; s/shapes: {count: 5, h: 0.1}/shapes: {count: 5, base: file, base_file: nowhere.stl}/' "shapes.base_file"
printf 'solid x\nendsolid x\n' > "$work/empty.stl"
expect surface_empty   "s|preset: random2d|preset: random3d|; s|shapes: {count: 5, h: 0.1}|shapes: {count: 5, base: file, base_file: $work/empty.stl}|" "empty.stl"
expect not_yaml        's/^shapes: {/shapes: {[/'                          "YAML"
# A directory family (base: directory, one shape per surface file of base_dir).
mkdir -p "$work/two_livers" "$work/no_surfaces" "$work/broken_dir"
cp "$src/configs/surfaces/livers/liver_000.stl" "$work/two_livers/a.stl"
cp "$src/configs/surfaces/livers/liver_001.stl" "$work/two_livers/b.stl"
echo "not a surface" > "$work/no_surfaces/readme.txt"
cp "$src/configs/surfaces/livers/liver_000.stl" "$work/broken_dir/a.stl"
cp "$work/empty.stl" "$work/broken_dir/b.stl"
liver() { echo "s|preset: random2d|preset: liver|; s|shapes: {count: 5, h: 0.1}|shapes: {$1}|"; }
expect dir_missing     "$(liver "base_dir: $work/nowhere")"                "shapes.base_dir: $work/nowhere: no such directory"
expect dir_is_file     "$(liver "base_dir: $work/empty.stl")"              "shapes.base_dir: $work/empty.stl: not a directory"
expect dir_no_surfaces "$(liver "base_dir: $work/no_surfaces")"            "shapes.base_dir: no surface files"
expect dir_broken_file "$(liver "base_dir: $work/broken_dir")"             "shapes.base_dir: $work/broken_dir/b.stl"
expect dir_count       "$(liver "count: 3, base_dir: $work/two_livers")"   "shapes.count: 3 shapes, but"
expect dir_steps_type  "$(liver "base_dir: $work/two_livers, steps: 0.2")" "shapes.steps"
expect dir_wrong_base  "s|preset: random2d|preset: random3d|; s|shapes: {count: 5, h: 0.1}|shapes: {count: 2, base_dir: $work/two_livers}|" \
                       "shapes.base_dir: only allowed with base: directory"
expect dir_in_2d       "s|shapes: {count: 5, h: 0.1}|shapes: {count: 2, base: directory, base_dir: $work/two_livers}|" \
                       "shapes.base: directory needs dim 3"
expect task_index      's/^seed: 7/seed: 7/'                               "--task-index" --task-index 3 --task-count 3
expect group_size      's/^seed: 7/seed: 7/'                               "--group-size" --group-size 4
mkdir -p "$work/readonly" && chmod 500 "$work/readonly"
if [ "$(id -u)" != 0 ]; then
  OUT="$work/readonly/sub" expect unwritable 's/^seed: 7/seed: 7/'        "-o"
fi
: > "$work/a_file"
OUT="$work/a_file" expect output_is_file 's/^seed: 7/seed: 7/'           "not a directory"
before=$(find "$work/np1" -type f | sort | xargs md5sum)
OUT="$work/np1" expect other_dataset 's/seed: 7/seed: 8/'                  "another dataset"
[ "$before" = "$(find "$work/np1" -type f | sort | xargs md5sum)" ] && ok "the other dataset is untouched" || fail "other dataset modified"
finish
