#!/usr/bin/python3
"""Cross-checks a 3D reference of study_labels3d with an independent solver (DOLFINx 0.5.2).

    scripts/check_labels3d_dolfinx.py results/labels3d/ball_ref.h5 [--out results/labels3d/dolfinx_ball_ref.json]

Reads a solution written by `study_labels3d --write DIR` (mesh, P2 displacement, the scene with
its alpha), builds the same problem in DOLFINx on the same mesh and P2 space (DolfinxScene of
scripts/bench_dolfinx.py: the seed's energy, the clamp, the Gaussian traction alpha g phi / I_N,
the same quadrature), solves it at the same alpha by load continuation (MUMPS LU), and prints
the relative L2 difference of the nodal fields and the two max|u|. Needs Debian's
python3-dolfinx; one process; OMP/BLAS threads 1.
"""
import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
import yaml

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_dolfinx as bd  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("solution")
    ap.add_argument("--out", default="")
    args = ap.parse_args()
    bd.import_dolfinx()
    import h5py
    with h5py.File(args.solution, "r") as f:
        raw = f["inputs/scene"][()]
        scene = yaml.safe_load(raw.decode() if isinstance(raw, bytes) else raw)
    hs = bd.read_hypershape(args.solution)
    alpha = float(scene["load"]["alpha"])
    t0 = time.time()
    dx = bd.DolfinxScene(scene, hs)
    gt = scene["effects"]["gaussian_traction"]
    dx.set_load_point(np.array(gt["center"], float), np.array(gt["direction"], float))
    dx.reset()
    ok = dx.solve_to(0.0, alpha)
    seconds = time.time() - t0
    u_dx = dx.node_values(hs["nodes"])
    u_hs = hs["u_last"]
    matched = np.isfinite(u_dx).all(axis=1)
    diff = np.sqrt(((u_dx[matched] - u_hs[matched]) ** 2).sum() / (u_hs[matched] ** 2).sum())
    out = {"solution": args.solution, "alpha": alpha, "converged": bool(ok), "nodes": int(len(u_hs)),
           "nodes_matched": int(matched.sum()), "dofs": int(3 * len(u_hs)),
           "rel_l2_difference": float(diff),
           "max_u_hypershape": float(np.sqrt((u_hs ** 2).sum(axis=1)).max()),
           "max_u_dolfinx": float(dx.max_u()),
           "dolfinx_newton_iterations": dx.newton_iterations, "dolfinx_seconds": seconds}
    print(json.dumps(out, indent=1))
    if args.out:
        Path(args.out).write_text(json.dumps(out, indent=1) + "\n")


if __name__ == "__main__":
    main()
