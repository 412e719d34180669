#!/usr/bin/env bash
# Path-following regressions on Random2D draws (P1 h 0.04: random2d_p1) of a seed nobody tuned on (issue 23), taken from
# the dataset's own loads/ arrays: seed 777 shape 6 load 0 (one task of 12 on 1 rank, ~15 s).
#  - Its last increment failed at the target and, when the step was longer than the remaining
#    way, the same failed increment was tried again: 186 Newton iterations before the fix
#    (`step = 0.5 (d_next - d)` in follow_path), 117 after. It must converge, to a stable state
#    (status 1), within 150.
# Needs HYPERSHAPE_BIN and HYPERSHAPE_SOURCE_DIR (set by CTest).
. "$(dirname "$0")/lib.sh"
cat > "$work/s777.yaml" <<'YAML'
preset: random2d_p1
name: s777
seed: 777
shapes: {count: 12}
loads: {count: 50}
representations: {grid_size: 16}
output: {shard_size: 1}
YAML
"$bin" -q generate "$work/s777.yaml" --task-index 6 --task-count 12 --progress 0 -o "$work/s777" ||
  fail "generate"
if out=$(/usr/bin/python3 - "$work/s777" <<'PY'
import glob, sys, h5py
(f,) = [h5py.File(p) for p in glob.glob(sys.argv[1] + "/shards/*.h5")]
L = f["shapes/000006/loads"]
status, its = int(L["status"][0]), int(L["newton_iterations"][0])
print(f"shape 6 load 0: status {status}, {its} Newton iterations")
sys.exit(0 if status == 1 and its <= 150 else 1)
PY
); then ok "$out"; else fail "$out (expected status 1 within 150 iterations)"; fi
finish
