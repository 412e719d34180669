#!/usr/bin/env python3
"""Compares two hypershape dataset directories array by array (not by hash): every dataset
and attribute of every shard, and manifest.json (less byte sizes and checksums, which follow
from the arrays), splits.json and stats.json. Exit 0 if identical, 1 with the differences.

  compare_datasets.py A B             bit for bit
  compare_datasets.py A B --rtol R    floating-point values within R * max|value| of the array
                                      (solver groups of several ranks sum in another order;
                                      the labels' error estimates, loads/error_estimate_*, are
                                      then only checked to be present with the same shape: see
                                      ESTIMATE_NOTE)
  ... --rtol R --paths-differ         also the path counters (PATH_ARRAYS: how the solver got
                                      there) and the reasons only checked for shape: two solvers
                                      that reach the same equilibria by other paths (a solver
                                      group does not relax patches: SolverOptions::local_relaxation)"""
import json
import os
import sys

import h5py
import numpy as np


def walk(group, prefix=""):
    for k, v in group.items():
        path = f"{prefix}/{k}"
        yield path, v
        if isinstance(v, h5py.Group):
            yield from walk(v, path)


RTOL = 0.0
# The error estimates come from GMRES at rtol 1e-2 and an energy line search on the refined mesh
# (src/solver/error_estimate.cpp): another partition changes them by 5e-3 typically, by 25% on
# a hard load case of the tiny h 0.1 dataset, and may turn one into -1 (no estimate). They are
# bit for bit on any number of ranks with solver groups of one rank (the default).
ESTIMATE_NOTE = "error estimates not compared under --rtol (partition-dependent)"
PATHS_DIFFER = False
PATH_ARRAYS = ("/solves", "/newton_iterations", "/failed_increments", "/recovery_iterations", "/reason")


def same(x, y):
    rtol = RTOL
    x, y = np.asarray(x), np.asarray(y)
    if x.shape != y.shape or x.dtype != y.dtype:
        return False
    if x.dtype.kind == "f":
        # NaN where both have it is the same value (e.g. the isoperimetric ratio of a 3D shape).
        nx, ny = np.isnan(x), np.isnan(y)
        if not np.array_equal(nx, ny):
            return False
        x, y = x[~nx], y[~ny]
    if rtol > 0 and x.dtype.kind == "f" and x.size:
        return bool(np.all(np.abs(x - y) <= rtol * max(np.abs(x).max(), 1e-300)))
    return bool(np.array_equal(x, y))


def same_json(a, b):
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(same_json(a[k], b[k]) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(same_json(x, y) for x, y in zip(a, b))
    if isinstance(a, float) and isinstance(b, float) and RTOL > 0:
        return abs(a - b) <= RTOL * max(abs(a), abs(b), 1e-300)
    return a == b


def compare_h5(a, b, errors):
    fa, fb = h5py.File(a, "r"), h5py.File(b, "r")
    ia, ib = dict(walk(fa)), dict(walk(fb))
    if set(ia) != set(ib):
        errors.append(f"{a}: objects differ: {sorted(set(ia) ^ set(ib))[:5]}")
    n = 0
    for path in sorted(set(ia) & set(ib)):
        x, y = ia[path], ib[path]
        for k in set(x.attrs) | set(y.attrs):
            if k not in x.attrs or k not in y.attrs or not same(x.attrs[k], y.attrs[k]):
                errors.append(f"{a}:{path}: attribute {k} differs")
        if isinstance(x, h5py.Dataset):
            n += 1
            if (RTOL > 0 and "/error_estimate_" in path) or (PATHS_DIFFER and path.endswith(PATH_ARRAYS)):
                if x.shape != y.shape:
                    errors.append(f"{a}:{path}: shapes differ")
                continue
            if not same(x[()], y[()]):
                errors.append(f"{a}:{path}: values differ")
    for k in set(fa.attrs) | set(fb.attrs):
        if not np.array_equal(fa.attrs.get(k), fb.attrs.get(k)):
            errors.append(f"{a}: file attribute {k} differs")
    return n


def main(da, db):
    errors = []
    sa = sorted(os.listdir(os.path.join(da, "shards")))
    sb = sorted(os.listdir(os.path.join(db, "shards")))
    if sa != sb:
        errors.append(f"shard lists differ: {sa} vs {sb}")
    n = 0
    for s in sorted(set(sa) & set(sb)):
        n += compare_h5(os.path.join(da, "shards", s), os.path.join(db, "shards", s), errors)
    for name in ["manifest.json", "splits.json", "stats.json"]:
        ja, jb = (json.load(open(os.path.join(d, name))) for d in (da, db))
        if name == "manifest.json":
            for j in (ja, jb):
                for s in j["shards"]:
                    s.pop("bytes"), s.pop("crc32")
        if not same_json(ja, jb):
            errors.append(f"{name} differs")
    for e in errors[:20]:
        print("DIFF", e)
    note = f" ({ESTIMATE_NOTE})" if RTOL > 0 else ""
    if PATHS_DIFFER:
        note += " (path counters and reasons not compared)"
    print(f"compared {len(sa)} shards, {n} arrays: {'identical' if not errors else f'{len(errors)} differences'}{note}")
    return 0 if not errors else 1


if __name__ == "__main__":
    if len(sys.argv) in (5, 6) and sys.argv[3] == "--rtol":
        RTOL = float(sys.argv[4])
        PATHS_DIFFER = sys.argv[5:] == ["--paths-differ"]
        if len(sys.argv) == 6 and not PATHS_DIFFER:
            sys.exit(f"unknown option {sys.argv[5]}")
    sys.exit(main(sys.argv[1], sys.argv[2]))
