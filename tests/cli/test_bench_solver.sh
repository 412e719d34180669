#!/usr/bin/env bash
# The first sample run of drivers/bench_solver.cpp's header (the disk, P1, h 0.1, one repeat: a
# second or two), taken from the header itself so that the two cannot drift apart. Asserts: exit
# 0, both tables printed, and a JSON whose one case converged in all three solves (alpha search,
# full solve, second load case) with finite timings of every phase.
source "$(dirname "$0")/lib.sh"
bench="$(dirname "$bin")/bench_solver"
[ -x "$bench" ] || { echo "FAIL: no $bench (build the bench_solver target)"; exit 1; }
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1
sample=$(grep -m1 '^///   bench_solver --dims 2 ' "$src/drivers/bench_solver.cpp" | sed 's|^///   bench_solver ||')
[ -n "$sample" ] && ok "sample run in the header: bench_solver $sample" || fail "no tiny sample run in the header"
cd "$work"
# shellcheck disable=SC2086
if "$bench" $sample > table.txt 2> progress.txt; then ok "bench_solver $sample"; else fail "exit $?"; cat progress.txt; fi
grep -q "Sizes, Newton iterations" table.txt && grep -q "Kernels at the converged state" table.txt &&
  ok "tables printed" || fail "tables missing"
json=$(sed -n 's/.*--json \([^ ]*\).*/\1/p' <<<"$sample")
/usr/bin/python3 - "$json" <<'PY' && ok "JSON checks" || fail "JSON checks"
import json, math, sys
b = json.load(open(sys.argv[1]))
assert b["benchmark"] == "bench_solver" and b["machine"]["nproc"] >= 1
(c,) = b["cases"]
assert c["error"] is None, c["error"]
v = c["values"]
for k in ("target_converged", "full_converged", "second_converged"):
    assert v[k] == 1, (k, v[k])
assert v["free_dofs"] > 0 and v["alpha"] > 0 and 1 <= v["full_newton"] <= 30, v
for k in ("mesh", "setup", "factor_first", "target_solve", "residual", "jacobian", "full_solve", "second_load"):
    t = c["median_seconds"][k]
    assert t is not None and math.isfinite(t) and t >= 0, (k, t)
print(f"{v['free_dofs']:.0f} DoFs, alpha {v['alpha']:.5g}, {v['full_newton']:.0f} Newton its")
PY
/usr/bin/python3 "$src/scripts/bench_solver_table.py" "$json" > table.md &&
  grep -q '^| 2 | P1 |' table.md && ok "scripts/bench_solver_table.py: the README's table from the JSON" ||
  fail "scripts/bench_solver_table.py"
finish
