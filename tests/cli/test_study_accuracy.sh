#!/usr/bin/env bash
# The accuracy/time study end to end in its tiny version (drivers/study_accuracy.cpp --tiny: the
# unit disk, P1 at h 0.16/0.08/0.04 and P2 at 0.16/0.08 against a P2 h 0.02 reference, one
# load case, one repeat), then the plot script. Asserts: every setting converged with finite
# errors; the error falls as h falls for P1 and for P2; P2 beats P1 at the same h; the
# reference's Richardson estimate (and its observed order) is reported and finite; the C++
# metrics agree with scripts/hypershape_data.py's rel_l2 / rel_h1 to round-off on the dumped
# arrays; the JSON, the markdown table and the Pareto PNG exist; an unwritable --out stops it
# before any work; a setting run on one scene of two is listed with its scene and kept off the fronts.
# Needs HYPERSHAPE_BIN (the study binary sits beside it) and HYPERSHAPE_SOURCE_DIR (set by CTest).
set -u
bin_dir=$(dirname "${HYPERSHAPE_BIN:?}")
src=${HYPERSHAPE_SOURCE_DIR:?}
study="$bin_dir/study_accuracy"
[ -x "$study" ] || { echo "FAIL: no $study (build the study_accuracy target)"; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1

# An unwritable output stops the study before any work (exit 2, the path and option named).
msg=$("$study" --tiny --out /proc/no/such/dir/study.json 2>&1 >/dev/null); code=$?
[ "$code" -eq 2 ] && grep -q -- "--out" <<<"$msg" && ! grep -q "\[study\]" <<<"$msg" ||
  { echo "FAIL: unwritable --out: exit $code, $msg"; exit 1; }

start=$(date +%s)
if ! "$study" --tiny --out "$work/study.json" --dump "$work/dump.json" > "$work/table.md" 2> "$work/progress.txt"; then
  echo "FAIL: study_accuracy --tiny"; cat "$work/progress.txt"; exit 1
fi
echo "study_accuracy --tiny: $(( $(date +%s) - start )) s"
cat "$work/progress.txt"
grep -q "reference" "$work/progress.txt" || { echo "FAIL: no progress lines"; exit 1; }
grep -q "| setting |" "$work/table.md" || { echo "FAIL: no markdown table printed"; exit 1; }

if ! /usr/bin/python3 "$src/scripts/plot_accuracy.py" "$work/study.json" --fig-dir "$work/fig" --suffix _tiny \
     --table "$work/study.md" > /dev/null; then
  echo "FAIL: plot_accuracy.py"; exit 1
fi

SRC="$src" PYTHONPATH="$src/scripts" /usr/bin/python3 - "$work" <<'PY'
import json, math, os, sys
import numpy as np
import hypershape_data as hd

work = sys.argv[1]
s = json.load(open(f"{work}/study.json"))
assert s["mode"] == "tiny", s["mode"]
assert s["machine"]["nproc"] >= 1 and s["machine"].get("cpu_model"), s["machine"]
(sc,) = s["scenes"]
assert sc["name"] == "disk" and sc["dim"] == 2 and "error" not in sc, sc.get("error")
ref = sc["reference"]
rich = ref["richardson"][0]
for k in ("l2", "h1", "alpha"):
    e = rich[k]["estimate"]
    assert e is not None and math.isfinite(e) and e > 0, (k, rich[k])
    assert rich[k]["order_observed"] is not None, (k, rich[k])
print(f"reference P2 h {ref['h']}: {ref['dofs']} DoFs, Richardson estimate of its own error: "
      f"L2 {rich['l2']['estimate']:.2e} (order {rich['l2']['order_observed']:.2f}), "
      f"H1 {rich['h1']['estimate']:.2e}, alpha {rich['alpha']['estimate']:.2e}")
assert ref["richardson_l2_mean"] is not None

err = {}
for r in sc["results"]:
    st = r["setting"]
    assert "error" not in r, (st["name"], r.get("error"))
    for lo in r["loads"]:
        assert lo["converged"], (st["name"], lo["reason"])
        for k in ("rel_l2", "rel_h1", "alpha_err", "seconds"):
            assert lo[k] is not None and math.isfinite(lo[k]) and lo[k] >= 0, (st["name"], k, lo[k])
        assert lo["rel_l2"] > 0 and lo["rel_h1"] > 0, st["name"]
    if st["group"] == "mesh":
        err[(st["degree"], st["h"])] = (r["summary"]["rel_l2"], r["summary"]["rel_h1"])
print("mesh settings (degree, h): (rel L2, rel H1):", err)
for p, hs in ((1, [0.16, 0.08, 0.04]), (2, [0.16, 0.08])):
    for coarse, fine in zip(hs, hs[1:]):
        for m in (0, 1):
            assert err[(p, fine)][m] < err[(p, coarse)][m], f"P{p}: error does not fall from h {coarse} to {fine}: {err}"
for h in (0.16, 0.08):
    assert err[(2, h)][0] < err[(1, h)][0], f"P2 is not more accurate than P1 at h {h}: {err}"
defaults = [r for r in sc["results"] if r["setting"]["is_default"]]
assert len(defaults) == 1 and defaults[0]["setting"]["name"] == "P1 h0.04", [r["setting"]["name"] for r in defaults]
# The same-load (training-pair) error: present for every converged load case, and for P1 close
# to the alpha error (the stiffness the target constraint moves into alpha), well above the
# same-target error (the study's first finding).
assert sc["same_load_pass"]["failed"] == 0 and sc["same_load_pass"]["solves"] >= 4, sc["same_load_pass"]
for r in sc["results"]:
    for lo in r["loads"]:
        v = lo.get("same_load_rel_l2")
        assert v is not None and math.isfinite(v) and v > 0, (r["setting"]["name"], lo.get("same_load_error"))
dl = defaults[0]["loads"][0]
assert dl["same_load_rel_l2"] > 2 * dl["rel_l2"], dl
assert 0.5 < dl["same_load_rel_l2"] / dl["alpha_err"] < 2, dl
tight = [r for r in sc["results"] if r["setting"]["group"] == "tolerance"][0]
assert defaults[0]["loads"][0]["solver_l2"] is not None and defaults[0]["loads"][0]["solver_l2"] < 1e-2

# One implementation per metric: the C++ values equal the Python readers' on the same arrays.
d = json.load(open(f"{work}/dump.json"))
dim, k = d["dim"], d["nodes_per_cell"]
nodes = np.array(d["nodes"]).reshape(-1, dim)
cells = np.array(d["cells"]).reshape(-1, k)
u = np.array(d["u_ref"]).reshape(-1, dim)
uh = np.array(d["u_hat"]).reshape(-1, dim)
l2, h1 = hd.rel_l2(u, uh), hd.rel_h1(u, uh, nodes, cells)
assert abs(l2 - d["rel_l2"]) <= 1e-10 * l2, (l2, d["rel_l2"])
assert abs(h1 - d["rel_h1"]) <= 1e-10 * h1, (h1, d["rel_h1"])
print(f"C++ vs hypershape_data ({d['setting']}): rel L2 {d['rel_l2']:.12e} vs {l2:.12e}, "
      f"rel H1 {d['rel_h1']:.12e} vs {h1:.12e}")

png = f"{work}/fig/accuracy_pareto_2d_tiny.png"
assert os.path.getsize(png) > 10000, png
assert open(png, "rb").read(8) == b"\x89PNG\r\n\x1a\n"
md = open(f"{work}/study.md").read()
assert "Pareto front" in md and "P1 h0.04 **(default)**" in md, md[:2000]
print("plot and table written")

# A setting run on one scene only (a knob of that scene's own baseline) is not compared with
# means over every scene: listed with its scene, off the fronts. The study with a second copy
# of the disk whose fastest setting is renamed, so that each of the two names covers one scene.
import copy, subprocess
two = copy.deepcopy(s)
other = copy.deepcopy(sc)
other["name"] = "disk-b"
fast = min((r for r in other["results"] if "error" not in r), key=lambda r: r["loads"][0]["seconds"])
lone = fast["setting"]["name"]
fast["setting"] = dict(fast["setting"], name=lone + " alone")
two["scenes"].append(other)
json.dump(two, open(f"{work}/two.json", "w"))
subprocess.run(["/usr/bin/python3", f"{os.environ['SRC']}/scripts/plot_accuracy.py", f"{work}/two.json",
                "--fig-dir", f"{work}/fig2", "--table", f"{work}/two.md"], check=True, stdout=subprocess.DEVNULL)
md2 = open(f"{work}/two.md").read()
fr = json.load(open(f"{work}/two_findings.json"))["2"]
assert f"{lone} alone [disk-b only: not on the fronts]" in md2, md2[:3000]
assert f"{lone} [disk only: not on the fronts]" in md2, md2[:3000]
assert lone not in fr["front"] and lone + " alone" not in fr["front"], fr["front"]
print(f"a setting on one scene of two ({lone}) is listed with its scene and left off the fronts")
PY
rc=$?
[ $rc -eq 0 ] && echo "PASS" || echo "FAIL"
exit $rc
