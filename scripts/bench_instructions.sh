#!/usr/bin/env bash
# Two builds of hypershape on the same small dataset slice under callgrind (valgrind): the
# instructions each executes, in total and in the pieces of a load case (solver, tangent,
# energy and residual passes, factorisation, local relaxation, shape draw, mesh, writes), side
# by side, and whether the two datasets are the same array for array. Instruction counts do not
# depend on the host's load (two runs of one binary agree to about 1e-5, gmsh's meshing to ~1e-3:
# allocation addresses and clocks move a few branches): where a change leaves the data bit for
# bit and the load spreads whole runs by more than the change (this 2-core VM: 5-15%), these are
# the figures to compare (they count work, not time: a memory-bound loop or a memset counted per
# byte weighs differently).
#   scripts/bench_instructions.sh OTHER_HYPERSHAPE [SHAPES] [LOADS]
#   PRESET=random3d SEED=4343 scripts/bench_instructions.sh /tmp/old/build/hypershape 1 3
# Environment: PRESET (default random2d), SEED (default 5151, a seed no tuning used),
# THIS_HYPERSHAPE (default build/hypershape). The two run at the same time, one per core
# (callgrind slows a run about 50x: 1 x 12 Random2D P2 load cases take ~3 minutes).
# Needs valgrind (Debian's `valgrind`). JSON: results/bench_instructions.json.
set -euo pipefail
cd "$(dirname "$0")/.."
other=${1:?usage: scripts/bench_instructions.sh OTHER_HYPERSHAPE [SHAPES] [LOADS]}
shapes=${2:-1} loads=${3:-12}
this=${THIS_HYPERSHAPE:-build/hypershape}
command -v valgrind > /dev/null || { echo "bench_instructions.sh: needs valgrind (apt-get install valgrind)" >&2; exit 2; }
[ -x "$other" ] || { echo "bench_instructions.sh: $other is not an executable" >&2; exit 2; }
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cat > "$work/slice.yaml" <<YAML
preset: ${PRESET:-random2d}
name: bench_instructions
seed: ${SEED:-5151}
shapes: {count: $shapes}
loads: {count: $loads}
YAML
for v in this other; do
  bin=$this
  [ $v = other ] && bin=$other
  valgrind --tool=callgrind --callgrind-out-file="$work/$v.out" "$bin" -q generate "$work/slice.yaml" \
    --progress 0 -o "$work/$v" > "$work/$v.log" 2>&1 &
done
wait
for v in this other; do callgrind_annotate --inclusive=yes --threshold=100 "$work/$v.out" > "$work/$v.txt" 2>/dev/null; done
# (compare_datasets exits 1 where they differ: that is a result to print, not an error here)
same=$({ /usr/bin/python3 tests/cli/compare_datasets.py "$work/other" "$work/this" 2>&1 || true; } | tail -1)
mkdir -p results
/usr/bin/python3 - "$work" "$other" "$same" <<'PY'
import json, re, sys
work, other, same = sys.argv[1:4]
# (label, a pattern of the inclusive function name in callgrind_annotate's output)
pieces = [
    ("whole process", r"PROGRAM TOTALS"),
    ("load cases: solve_for_target", r"NonlinearSolver::solve_for_target\("),
    ("  tangent assembly (Problem::jacobian)", r"physics::Problem::jacobian\("),
    ("  numeric factorisation (Tangent::factorise)", r"solver::Tangent::factorise\("),
    ("  energy + residual passes (energy_residual)", r"physics::Problem::energy_residual\("),
    ("  residual passes (Problem::residual)", r"physics::Problem::residual\("),
    ("  energy passes (Problem::energy)", r"physics::Problem::energy\("),
    ("  local relaxation (LocalRelaxation::relax)", r"LocalRelaxation::relax\("),
    ("  second-order terms (curvature_along_step)", r"NonlinearSolver::curvature_along_step\("),
    ("shape draw (make_shape)", r"factory::make_shape\("),
    ("mesh (gmsh)", r"mesh::\(anonymous namespace\)::run_gmsh\("),
    ("writes (ShardWriter::add)", r"io::ShardWriter::add\("),
]
def counts(path):
    text = open(path).read()
    out = {}
    for label, pat in pieces:
        m = re.search(r"^\s*([\d,]+) \([ \d.]+%\)\s+(?:\*\s+)?\S*" + pat, text, re.M) if label != "whole process" \
            else re.search(r"^\s*([\d,]+) \([ \d.]+%\)\s+PROGRAM TOTALS", text, re.M)
        out[label] = int(m.group(1).replace(",", "")) if m else None
    return out
c = {v: counts(f"{work}/{v}.txt") for v in ("this", "other")}
print(f"instructions (callgrind), this build against {other}; datasets: {same}")
print("| piece | this (G) | other (G) | this / other |")
print("|---|---|---|---|")
for label, _ in pieces:
    a, b = c["this"][label], c["other"][label]
    ratio = f"{a / b:.3f}" if a and b else "-"
    fmt = lambda x: f"{x / 1e9:.3f}" if x is not None else "-"
    print(f"| {label} | {fmt(a)} | {fmt(b)} | {ratio} |")
json.dump({"other": other, "datasets": same, "instructions": c}, open("results/bench_instructions.json", "w"), indent=1)
print("JSON: results/bench_instructions.json")
PY
