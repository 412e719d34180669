#!/usr/bin/env bash
# The first sample run of drivers/bench_shapes.cpp's header (Random2D shape 0 on a 32^2 grid: a
# second or two), taken from the header itself so that the two cannot drift apart. Asserts: exit
# 0, the table printed, and a JSON whose one preset made its shape with finite stage timings and
# a grid inside-measure close to the shape's measure.
source "$(dirname "$0")/lib.sh"
bench="$(dirname "$bin")/bench_shapes"
[ -x "$bench" ] || { echo "FAIL: no $bench (build the bench_shapes target)"; exit 1; }
sample=$(grep -m1 '^///   bench_shapes configs/.*--grid2d' "$src/drivers/bench_shapes.cpp" | sed 's|^///   bench_shapes ||')
[ -n "$sample" ] && ok "sample run in the header: bench_shapes $sample" || fail "no tiny sample run in the header"
cd "$work"
ln -s "$src/configs" configs  # the sample's paths are relative to the source tree
# shellcheck disable=SC2086
if "$bench" $sample > table.txt 2> progress.txt; then ok "bench_shapes $sample"; else fail "exit $?"; cat progress.txt; fi
grep -q "Per-shape timings" table.txt && grep -q "^random2d " table.txt && ok "table printed" || fail "table missing"
json=$(sed -n 's/.*--json \([^ ]*\).*/\1/p' <<<"$sample")
/usr/bin/python3 - "$json" <<'PY' && ok "JSON checks" || fail "JSON checks"
import json, math, sys
b = json.load(open(sys.argv[1]))
assert b["benchmark"] == "bench_shapes" and not b["skipped"], b["skipped"]
(p,) = b["presets"]
assert p["name"] == "random2d" and p["error"] is None and p["repeats"] == 1, p
for k in ("draw", "mesh", "metrics", "make_shape", "sdf_grid", "patch_grid", "total"):
    t = p["median_seconds"][k]
    assert t is not None and math.isfinite(t) and t >= 0, (k, t)
v = p["median_values"]
assert v["cells"] > 0 and v["boundary_facets"] > 0, v
assert abs(v["grid_inside_measure"] / v["measure"] - 1) < 0.2, v
print(f"{v['boundary_facets']:.0f} boundary facets, {v['cells']:.0f} cells, measure {v['measure']:.3f}")
PY
/usr/bin/python3 "$src/scripts/bench_shapes_table.py" "$json" > table.md &&
  grep -q '^| random2d |' table.md && ok "scripts/bench_shapes_table.py: the README's table from the JSON" ||
  fail "scripts/bench_shapes_table.py"
finish
