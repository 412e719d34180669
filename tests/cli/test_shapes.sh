#!/usr/bin/env bash
# `hypershape shapes`: the same shapes on 1 and 3 ranks (bit for bit), and bad dataset configs
# fail with a message naming the file and the key, a non-zero exit and no output file.
# Needs HYPERSHAPE_BIN and HYPERSHAPE_SOURCE_DIR (set by CTest).
. "$(dirname "$0")/lib.sh"

# ---- rank independence -------------------------------------------------------------------
preset="$src/configs/presets/random2d.yaml"
if ! "$bin" -q shapes "$preset" -n 6 -o "$work/np1.h5"; then echo "FAIL: 1-rank run"; exit 1; fi
if ! mpiexec -n 3 --oversubscribe "$bin" -q shapes "$preset" -n 6 -o "$work/np3.h5"; then
  echo "FAIL: 3-rank run"; exit 1
fi
/usr/bin/python3 - "$work/np1.h5" "$work/np3.h5" <<'PY' || fails=$((fails+1))
import sys, h5py, numpy as np
a, b = h5py.File(sys.argv[1]), h5py.File(sys.argv[2])
assert list(a["shapes"]) == list(b["shapes"]) and len(a["shapes"]) == 6, "different shape ids"
for sid in a["shapes"]:
    ga, gb = a["shapes"][sid], b["shapes"][sid]
    for name in ["boundary/points", "boundary/facets", "mesh/nodes", "mesh/cells", "dirichlet_facets"]:
        assert np.array_equal(ga[name][()], gb[name][()]), f"shape {sid}: {name} differs"
    for k, v in ga.attrs.items():
        if not k.startswith("seconds"):
            assert np.array_equal(v, gb.attrs[k]), f"shape {sid}: attribute {k} differs"
print("1 and 3 ranks: identical shapes", list(a["shapes"]))
PY
passes=$((passes+1))

# ---- bad configs -------------------------------------------------------------------------
good() {
  cat <<'YAML'
name: t
seed: 1
shapes:
  count: 2
  dim: 2
  base: circle
  steps: [[0.2, 1]]
  h: 0.1
  dirichlet_radius: 0.5
YAML
}
# expect NAME SED-EXPRESSION EXPECTED-KEY-TEXT
expect() {
  local name=$1 expr=$2 key=$3 cfg="$work/$1.yaml" out="$work/$1.h5"
  good | sed -e "$expr" > "$cfg"
  local msg code
  msg=$("$bin" shapes "$cfg" -o "$out" 2>&1 >/dev/null); code=$?
  if [ "$code" -eq 0 ]; then echo "FAIL $name: exit 0"; fails=$((fails+1)); return; fi
  if ! grep -qF "$cfg" <<<"$msg"; then echo "FAIL $name: message does not name the file: $msg"; fails=$((fails+1)); return; fi
  if ! grep -qF -- "$key" <<<"$msg"; then echo "FAIL $name: message does not name '$key': $msg"; fails=$((fails+1)); return; fi
  if ls "$work/$1".h5* >/dev/null 2>&1; then echo "FAIL $name: left output behind"; fails=$((fails+1)); return; fi
  echo "ok   $name: $msg"; passes=$((passes+1))
}
expect unknown_key      's/  h: 0.1/  h: 0.1\n  colour: red/'          "shapes.colour"
expect bad_dim          's/dim: 2/dim: 4/'                             "shapes.dim"
expect sphere_in_2d     's/base: circle/base: sphere/'                 "shapes.base"
expect bad_base         's/base: circle/base: blob/'                   "shapes.base"
expect bad_step         's/steps: \[\[0.2, 1\]\]/steps: [[0.2]]/'       "shapes.steps[0]"
expect negative_sigma   's/steps: \[\[0.2, 1\]\]/steps: [[-0.2, 1]]/'   "shapes.steps[0]"
expect no_steps         's/steps: \[\[0.2, 1\]\]/steps: []/'            "shapes.steps"
expect h_range          's/h: 0.1/h: 5/'                               "shapes.h"
expect count_zero       's/count: 2/count: 0/'                         "shapes.count"
expect missing_seed     '/^seed/d'                                     "seed"
expect top_unknown      '$a colour: red'                              "colour"
expect missing_surface  's/dim: 2/dim: 3/; s/base: circle/base: file\n  base_file: nowhere.stl/' "shapes.base_file"
printf 'solid x\nendsolid x\n' > "$work/empty.stl"
expect empty_surface    "s|dim: 2|dim: 3|; s|base: circle|base: file\n  base_file: $work/empty.stl|" "empty.stl"
expect not_yaml         's/^shapes:/shapes: [/'                        "YAML"
mkdir -p "$work/broken_dir"
cp "$src/configs/surfaces/livers/liver_000.stl" "$work/broken_dir/a.stl"
cp "$work/empty.stl" "$work/broken_dir/b.stl"
expect broken_in_dir    "s|dim: 2|dim: 3|; s|base: circle|base: directory\n  base_dir: $work/broken_dir|" "shapes.base_dir: $work/broken_dir/b.stl"
finish
