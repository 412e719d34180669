"""scripts/plot_grading.py, the picture of the 2D presets' grading at the patch ends
(docs/figures/grading_2d.png):
  - from the shipped study lines it writes a PNG, and its medians are the ones docs/ACCURACY.md
    quotes (random2d 1.30% as drawn, 0.98% at h/16, 0.67% at h/32, the preset; easy_random2d
    1.68% -> 0.69% -> 0.40%; one_random2d 1.21% -> 0.39%), each on the same load cases;
  - a preset file without a grading in its label takes the preset's own mesh.rim / shapes.h;
  - a family with a single setting, a label it cannot read, a missing file, a line that is not
    JSON or a preset that does not exist stops it with exit code 1 and a message naming it
    (no traceback), writing no file.
Needs HYPERSHAPE_SOURCE_DIR (set by CTest)."""
import glob
import json
import os
import subprocess
import sys
import tempfile

src = os.environ["HYPERSHAPE_SOURCE_DIR"]
sys.path.insert(0, os.path.join(src, "scripts"))
import plot_grading as pg  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import checks  # noqa: E402
from checks import check  # noqa: E402

script = os.path.join(src, "scripts", "plot_grading.py")
files = sorted(glob.glob(os.path.join(src, "docs", "error_estimate", "rim", "*.jsonl")))
data = pg.load(files)
medians = {f: [round(100 * s["median"], 2) for s in pg.summarise(data[f])] for f in data}
check(medians == {"random2d": [1.30, 0.98, 0.67], "easy_random2d": [1.68, 0.69, 0.40], "one_random2d": [1.21, 0.39]},
      f"the medians docs/ACCURACY.md quotes, as drawn first: {medians}")
check(sorted(data["random2d"]) == [0.0, 0.03125, 0.0625], f"random2d's preset file read as h/32: {sorted(data['random2d'])}")
counts = {f: {s["n"] for s in pg.summarise(data[f])} for f in data}
check(counts == {"random2d": {13}, "easy_random2d": {13}, "one_random2d": {9}}, f"one set of load cases per family: {counts}")

with tempfile.TemporaryDirectory() as tmp:
    png = os.path.join(tmp, "g.png")
    r = subprocess.run([sys.executable, script, "--out", png, *files], capture_output=True, text=True)
    check(r.returncode == 0 and os.path.getsize(png) > 10000 and "| random2d | h/32 | 13 | 0.67%" in r.stdout,
          f"writes a PNG and the table from {len(files)} files: exit {r.returncode}, {r.stderr.strip()}")
    one = [f for f in files if f.endswith("random2d_graded0.jsonl") and "easy" not in f and "one_" not in f]
    png2 = os.path.join(tmp, "h.png")
    r = subprocess.run([sys.executable, script, "--out", png2, *one], capture_output=True, text=True)
    check(r.returncode == 1 and "one setting only" in r.stderr and not os.path.exists(png2),
          f"one setting of random2d: exit {r.returncode}, {r.stderr.strip()}")
    bad = os.path.join(tmp, "bad.jsonl")
    with open(bad, "w") as f:
        f.write(json.dumps({"case": "disk P2", "shape": 0, "load": 0, "converged": True, "true_rel_l2": 0.01}) + "\n")
    r = subprocess.run([sys.executable, script, "--out", png2, bad], capture_output=True, text=True)
    check(r.returncode == 1 and "bad.jsonl" in r.stderr and "disk P2" in r.stderr and not os.path.exists(png2),
          f"an unreadable label: exit {r.returncode}, {r.stderr.strip()}")
    missing = os.path.join(tmp, "missing.jsonl")
    r = subprocess.run([sys.executable, script, "--out", png2, missing], capture_output=True, text=True)
    check(r.returncode == 1 and "missing.jsonl" in r.stderr and "Traceback" not in r.stderr and not os.path.exists(png2),
          f"a file that is not there: exit {r.returncode}, {r.stderr.strip()}")
    garbled = os.path.join(tmp, "garbled.jsonl")
    with open(garbled, "w") as f:
        f.write('{"case": "random2d-P2-h0.12", "shape"\n')
    r = subprocess.run([sys.executable, script, "--out", png2, garbled], capture_output=True, text=True)
    check(r.returncode == 1 and "garbled.jsonl:1" in r.stderr and "Traceback" not in r.stderr and not os.path.exists(png2),
          f"a line that is not JSON: exit {r.returncode}, {r.stderr.strip()}")
    unknown = os.path.join(tmp, "unknown.jsonl")
    with open(unknown, "w") as f:
        f.write(json.dumps({"case": "nosuch2d-P2-h0.12", "shape": 0, "load": 0, "converged": True, "true_rel_l2": 0.01}) + "\n")
    r = subprocess.run([sys.executable, script, "--out", png2, unknown], capture_output=True, text=True)
    check(r.returncode == 1 and "nosuch2d" in r.stderr and "Traceback" not in r.stderr and not os.path.exists(png2),
          f"a preset that does not exist: exit {r.returncode}, {r.stderr.strip()}")
sys.exit(1 if checks.failures else 0)
