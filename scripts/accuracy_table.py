#!/usr/bin/env python3
"""The cost-of-accuracy table of docs/ACCURACY.md (issue 19, "Datasets asked for by accuracy"):
one row per generated dataset directory, from its run report (reports/*.json: load cases, Newton
iterations, factorisations, the accuracy block) and its shards (the stored estimates, the level
each shape kept); CPU seconds from a /usr/bin/time log when given.

  accuracy_table.py DIR... [--times times.log]

times.log lines: "<name> cpu_user U cpu_sys S wall W ..." where <name> is DIR's basename less
"out_" (scripts in docs/ACCURACY.md write it)."""
import argparse
import glob
import json
import os

import h5py
import numpy as np


def cpu_seconds(path):
    out = {}
    if path:
        for line in open(path):
            w = line.split()
            if len(w) >= 5 and w[1] == "cpu_user":
                out[w[0]] = float(w[2]) + float(w[4])
    return out


def row(d, cpu):
    rep = json.load(open(sorted(glob.glob(f"{d}/reports/*.json"))[0]))
    s, lc = rep["solver"], rep["load_cases"]
    n_ok = lc["converged"]
    est, levels, dofs = [], [], []
    for f in sorted(glob.glob(f"{d}/shards/*.h5")):
        with h5py.File(f) as h:
            for g in h["shapes"].values():
                levels.append(int(g.attrs.get("accuracy_level", 0)))
                dofs.append(g["nodes"].shape[0] * g["nodes"].shape[1])
                if "error_estimate_rel_l2" in g["loads"]:
                    st = g["loads/status"][...]
                    est += list(g["loads/error_estimate_rel_l2"][...][st == 1])
    est = np.array(est)
    acc = rep.get("accuracy", {})
    name = os.path.basename(os.path.normpath(d)).removeprefix("out2_").removeprefix("out_")
    bound = acc.get("rel_l2_bound")
    meets = f"{100 * acc['share_meeting']:.1f}%" if acc else "-"
    lv = ", ".join(f"{k}: {levels.count(k)}" for k in sorted(set(levels))) if acc else "-"
    per = lambda k: s[k] / max(1, n_ok)
    e = (f"{np.median(est):.3g} / {np.max(est):.3g}" if len(est) else "-")
    c = cpu.get(name)
    return (f"| {name} | {bound if bound else '-'} | {n_ok}/{lc['converged'] + lc['failed']} | {meets} | {lv} | "
            f"{np.mean(dofs):.0f} | {e} | {per('newton_iterations'):.1f} | {per('numeric_factorizations'):.1f} | "
            f"{acc.get('discarded_load_cases', 0)} | {f'{c:.0f}' if c else '-'} | {f'{c / max(1, n_ok):.2f}' if c else '-'} |")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("dirs", nargs="+")
    ap.add_argument("--times")
    a = ap.parse_args()
    cpu = cpu_seconds(a.times)
    print("| run | bound | converged | estimate <= bound | shapes per level | mean unknowns | estimate median / max "
          "| Newton its per load case | factorisations per load case | discarded load cases | CPU s | CPU s per load case |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for d in a.dirs:
        print(row(d, cpu))


if __name__ == "__main__":
    main()
