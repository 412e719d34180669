#!/usr/bin/python3
"""Follower against dead pressure: what the non-symmetric path costs (LU factorisations, the
residual-work line search, one LDL^T of (K + K^T)/2 per target solve for the stability check)
against the symmetric one (LDL^T, the energy line search), in paired runs of the same scenes.

Usage: scripts/bench_follower.py BUILD_DIR [pairs] [repeat]
Each pair runs `hypershape solve SCENE --repeat R -log_view` with follower: false, then true
(the order alternating between pairs); per run: CPU seconds of the process (user + sys),
Newton iterations (the h5 file's), HSFactor and HSStability counts and seconds (-log_view).
Prints a table and one JSON line per scene."""
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile

import h5py

HERE = os.path.dirname(os.path.abspath(__file__))
DISK = """geometry: {base: circle}
mesh: {h: 0.04, degree: 1, clamp_refinement: 0.25}
effects:
  neo_hookean: {E: 500, nu: 0.4}
  dirichlet_patch: {center: [1.0, 0.0], radius: 0.5}
  pressure: {value: 1.0, center: [-1.0, 0.0], radius: 0.8, follower: true}
load: {target: 0.1}
"""


def run(binary, scene, repeat, work):
    out = os.path.join(work, "out.h5")
    p = subprocess.Popen([binary, "solve", scene, "-o", out, "--repeat", str(repeat), "-log_view"],
                         stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    text = p.stdout.read()
    _, status, ru = os.wait4(p.pid, 0)
    if status != 0:
        raise RuntimeError(f"{scene}: exit {status}\n{text[-2000:]}")
    events = {}
    for name in ("HSFactor", "HSStability"):
        m = re.search(rf"^{name}\s+(\d+)\s+\S+\s+(\S+)", text, re.M)
        events[name] = (int(m.group(1)), float(m.group(2))) if m else (0, 0.0)
    with h5py.File(out, "r") as f:
        its, alpha = int(f.attrs["newton_iterations"]), float(f.attrs["alpha"])
    return {"cpu": ru.ru_utime + ru.ru_stime, "newton": its, "alpha": alpha,
            "factor": events["HSFactor"], "stability": events["HSStability"]}


def main():
    build = sys.argv[1]
    pairs = int(sys.argv[2]) if len(sys.argv) > 2 else 5
    repeat = int(sys.argv[3]) if len(sys.argv) > 3 else 3
    binary = os.path.join(build, "hypershape")
    with tempfile.TemporaryDirectory() as work:
        with open(os.path.join(work, "disk.yaml"), "w") as f:
            f.write(DISK)
        cantilever = os.path.join(HERE, "..", "configs", "scenes", "follower_pressure.yaml")
        for name, src in (("cantilever P2 (follower_pressure.yaml)", cantilever),
                          ("disk P1 h 0.04, pressure near (-1, 0)", os.path.join(work, "disk.yaml"))):
            text = open(src).read()
            scenes = {}
            for kind in ("false", "true"):
                scenes[kind] = os.path.join(work, f"{kind}.yaml")
                with open(scenes[kind], "w") as f:
                    f.write(text.replace("follower: true", f"follower: {kind}"))
            res = {"false": [], "true": []}
            for k in range(pairs):
                for kind in (("false", "true") if k % 2 == 0 else ("true", "false")):
                    res[kind].append(run(binary, scenes[kind], repeat, work))
            dead, fol = res["false"], res["true"]
            ratio = [f["cpu"] / d["cpu"] for d, f in zip(dead, fol)]
            row = {"scene": name, "pairs": pairs, "repeat": repeat,
                   "newton": [dead[0]["newton"], fol[0]["newton"]],
                   "alpha": [dead[0]["alpha"], fol[0]["alpha"]],
                   "factorisations_per_solve": [dead[0]["factor"][0] / repeat, fol[0]["factor"][0] / repeat],
                   "stability_ldlt_per_solve": [dead[0]["stability"][0] / repeat, fol[0]["stability"][0] / repeat],
                   "seconds_per_factorisation": [statistics.median(r["factor"][1] / max(r["factor"][0], 1) for r in x)
                                                 for x in (dead, fol)],
                   "cpu_ratio_median": statistics.median(ratio), "cpu_ratio_min": min(ratio), "cpu_ratio_max": max(ratio)}
            print(f"{name}: Newton its dead {row['newton'][0]}, follower {row['newton'][1]}; factorisations per solve "
                  f"{row['factorisations_per_solve'][0]:g} (LDL^T) vs {row['factorisations_per_solve'][1]:g} (LU) + "
                  f"{row['stability_ldlt_per_solve'][1]:g} (LDL^T of the symmetric part); seconds per factorisation "
                  f"{row['seconds_per_factorisation'][0]:.2e} vs {row['seconds_per_factorisation'][1]:.2e}; CPU follower / dead "
                  f"median {row['cpu_ratio_median']:.2f} (min {row['cpu_ratio_min']:.2f}, max {row['cpu_ratio_max']:.2f}) "
                  f"over {pairs} pairs; alpha dead {row['alpha'][0]:.6g}, follower {row['alpha'][1]:.6g}")
            print(json.dumps(row))


if __name__ == "__main__":
    main()
