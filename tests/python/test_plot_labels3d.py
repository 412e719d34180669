"""scripts/plot_labels3d.py, the 3D label study's picture (docs/figures/labels3d_pareto.png):
  - from the shipped study JSONs it writes a PNG, and the points it plots are the JSONs' own
    (the preset of 2026-11-26 at 3.49% on r3d-0 and 2.92% on the ball, 4.46% for 2026-11-25);
  - the Pareto front is the fewest unknowns for the error: no plotted option is below it;
  - a JSON without results against refm0.0125 stops it with exit code 1 and a message naming
    the scene, writing no file.
Needs HYPERSHAPE_SOURCE_DIR (set by CTest)."""
import glob
import json
import os
import subprocess
import sys
import tempfile

src = os.environ["HYPERSHAPE_SOURCE_DIR"]
sys.path.insert(0, os.path.join(src, "scripts"))
import plot_labels3d as pl  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import checks  # noqa: E402
from checks import check  # noqa: E402

script = os.path.join(src, "scripts", "plot_labels3d.py")
files = sorted(glob.glob(os.path.join(src, "docs", "labels3d", "*_mean*.json")))
with tempfile.TemporaryDirectory() as tmp:
    png = os.path.join(tmp, "p.png")
    r = subprocess.run([sys.executable, script, "--out", png, *files], capture_output=True, text=True)
    check(r.returncode == 0 and os.path.getsize(png) > 10000, f"writes a PNG from {len(files)} study files: {r.stdout.strip()}")
    r3, ball = pl.options(files, "r3d-0"), pl.options(files, "ball")
    check(round(r3["s0.22i0.3rim12m"][1], 2) == 3.49 and round(ball["s0.22i0.3rim12m"][1], 2) == 2.92,
          f"the preset's points: r3d-0 {r3['s0.22i0.3rim12m']}, ball {ball['s0.22i0.3rim12m']}")
    check(round(r3["rim0.25m10"][1], 2) == 4.46, f"the 2026-11-25 preset on r3d-0: {r3['rim0.25m10']}")
    for scene, pts in (("r3d-0", r3), ("ball", ball)):
        fr = pl.front(pts)
        # No option has a smaller error than the front reaches with at most its unknowns.
        below = [n for n, (d, e) in pts.items() if e < min(fe for fd, fe in fr if fd <= d)]
        check(not below and fr == sorted(fr) and all(b[1] < a[1] for a, b in zip(fr, fr[1:])),
              f"{scene}: front of {len(fr)} points, every option on or above it")
    bad = os.path.join(tmp, "bad.json")
    json.dump({"scene": "ball", "reference": "ref0.0125", "results": []}, open(bad, "w"))
    png2 = os.path.join(tmp, "q.png")
    r = subprocess.run([sys.executable, script, "--out", png2, bad], capture_output=True, text=True)
    check(r.returncode == 1 and "r3d-0" in r.stderr and "refm0.0125" in r.stderr and not os.path.exists(png2),
          f"no results against refm0.0125: exit {r.returncode}, {r.stderr.strip()}")
sys.exit(1 if checks.failures else 0)
