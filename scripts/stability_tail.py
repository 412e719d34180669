#!/usr/bin/python3
"""What the slow tail of a dataset's load cases has in common (docs/STABILITY.md, issue 23).

  stability_tail.py DATASET_DIR...

The tail: load cases whose Newton iterations (loads/newton_iterations) exceed 3x the median (the
issue's p99 / p50 target). Prints, tail against the rest, the medians of the target, the distance
from the load's centre p_N to the clamped patch (|p_N - p_D| - r: < 0 inside it), min det F, alpha,
the shape's smallest local feature size, increments and failed increments; then the tail's share
by target and by that distance."""
import glob
import sys

import h5py
import numpy as np

KEYS = ("target", "to_clamp", "min_det_f", "alpha", "feature", "increments", "failed")


def rows(dirs):
    for d in dirs:
        for f in sorted(glob.glob(f"{d}/shards/*.h5")):
            with h5py.File(f) as h:
                for g in h["shapes"].values():
                    L = g["loads"]
                    if "newton_iterations" not in L:
                        continue
                    p_d, r = np.asarray(g.attrs["dirichlet_center"])[:2], float(g.attrs["dirichlet_radius"])
                    for k in range(len(L["newton_iterations"])):
                        yield dict(its=L["newton_iterations"][k], target=L["target"][k],
                                   to_clamp=np.linalg.norm(L["p_n"][k][:2] - p_d) - r, min_det_f=L["min_det_f"][k],
                                   alpha=L["alpha"][k], feature=g.attrs["min_local_feature_size"],
                                   increments=L["solves"][k], failed=L["failed_increments"][k])


def share(name, v, tail, edges):
    for lo, hi in zip(edges[:-1], edges[1:]):
        m = (v >= lo) & (v < hi)
        print(f"  {name} [{lo:g}, {hi:g}): {m.sum()} load cases, {100 * tail[m].mean() if m.any() else 0:.1f}% in the tail")


def main(dirs):
    data = list(rows(dirs))
    if not data:
        print("no load cases", file=sys.stderr)
        return 1
    its = np.array([r["its"] for r in data], float)
    tail = its > 3 * np.median(its)
    print(f"{len(its)} load cases: Newton its median {np.median(its):g}, p99 {np.percentile(its, 99):g}; "
          f"{tail.sum()} ({100 * tail.mean():.1f}%) above 3x the median")
    for k in KEYS:
        v = np.array([r[k] for r in data], float)
        t = (f"tail median {np.median(v[tail]):.3g} (p10-p90 {np.percentile(v[tail], 10):.3g}-"
             f"{np.percentile(v[tail], 90):.3g})" if tail.any() else "no tail")
        print(f"  {k:>10}: {t}, the rest {np.median(v[~tail]):.3g}")
    share("target", np.array([r["target"] for r in data]), tail, [0, 0.2, 0.3, 0.4, 0.5, 2])
    share("p_N to the patch", np.array([r["to_clamp"] for r in data]), tail, [-9, 0.1, 0.3, 0.6, 9])
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
