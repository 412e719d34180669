#!/usr/bin/env python3
"""Cook's membrane mesh convergence (configs/scenes/cook_membrane.yaml): solves the scene at
each element size and degree and prints u_y at the corner (48, 60) against the literature's
6.9083 (Elguedj et al. 2008, 128 x 128 mesh), as a markdown table and as JSON lines.

    scripts/cook_membrane.py [--bin build/hypershape] [--h 4,2,1,0.5] [--degrees 2,1]
"""
import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time

import h5py
import numpy as np

REFERENCE = 6.9083
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def corner_uy(path):
    with h5py.File(path, "r") as f:
        x, u = f["mesh/nodes"][()], f["fields/displacement"][()]
    i = int(np.argmin(np.hypot(x[:, 0] - 48.0, x[:, 1] - 60.0)))
    assert abs(x[i, 0] - 48) < 1e-12 and abs(x[i, 1] - 60) < 1e-12, x[i]
    return float(u[i, 1])


def solve(binary, scene_text, h, degree, work):
    text = re.sub(r"mesh: \{[^}]*\}", f"mesh: {{h: {h}, degree: {degree}}}", scene_text)
    scene, out = os.path.join(work, "cook.yaml"), os.path.join(work, "cook.h5")
    with open(scene, "w") as f:
        f.write(text)
    t0 = time.time()
    run = subprocess.run([binary, "solve", scene, "-o", out], capture_output=True, text=True)
    seconds = time.time() - t0
    line = (run.stdout + run.stderr).strip().splitlines()[-1] if (run.stdout + run.stderr).strip() else ""
    dofs = re.search(r"(\d+) dofs", line)
    ok = run.returncode == 0 and "NOT converged" not in line
    return {"h": h, "degree": degree, "dofs": int(dofs.group(1)) if dofs else 0, "converged": ok,
            "uy": corner_uy(out) if ok else float("nan"), "seconds": round(seconds, 2)}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bin", default=os.path.join(ROOT, "build", "hypershape"))
    ap.add_argument("--scene", default=os.path.join(ROOT, "configs", "scenes", "cook_membrane.yaml"))
    ap.add_argument("--h", default="4,2,1,0.5")
    ap.add_argument("--degrees", default="2,1")
    a = ap.parse_args()
    text = open(a.scene).read()
    rows = []
    with tempfile.TemporaryDirectory() as work:
        for degree in [int(d) for d in a.degrees.split(",")]:
            for h in [float(v) for v in a.h.split(",")]:
                r = solve(a.bin, text, h, degree, work)
                rows.append(r)
                print(json.dumps(r), file=sys.stderr, flush=True)
    print(f"| degree | h | dofs | u_y(48, 60) | vs {REFERENCE} | seconds |")
    print("|---|---|---|---|---|---|")
    for r in rows:
        rel = (r["uy"] / REFERENCE - 1) * 100
        print(f"| P{r['degree']} | {r['h']:g} | {r['dofs']} | {r['uy']:.4f} | {rel:+.2f}% | {r['seconds']} |")


if __name__ == "__main__":
    main()
