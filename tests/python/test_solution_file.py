"""`hypershape solve` writes a readable HDF5 file (+ XDMF) whose arrays are consistent: every
node referenced, displacement finite, max |u| equal to the recorded target within 1e-3."""
import os
import subprocess
import sys
import tempfile

import h5py
import numpy as np

bin_ = os.environ["HYPERSHAPE_BIN"]
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import checks  # noqa: E402
from checks import check  # noqa: E402


with tempfile.TemporaryDirectory() as d:
    out = os.path.join(d, "default.h5")
    run = subprocess.run([bin_, "solve", "-o", out], capture_output=True, text=True)
    check(run.returncode == 0, f"default scene solves (exit {run.returncode}) {run.stdout.strip()} {run.stderr.strip()}")
    check(os.path.exists(out[:-3] + ".xdmf"), "XDMF written beside the HDF5 file")
    check(not [f for f in os.listdir(d) if ".tmp-" in f], "no temporary file left")
    with h5py.File(out, "r") as f:
        nodes, cells, u = f["mesh/nodes"][...], f["mesh/cells"][...], f["fields/displacement"][...]
        check(nodes.shape[1] == 2 and cells.shape[1] == 3, f"2D P1 shapes {nodes.shape} {cells.shape}")
        check(u.shape == nodes.shape, "one displacement per node")
        check(np.isfinite(u).all(), "displacement finite")
        check(set(np.unique(cells)) == set(range(len(nodes))), "every node belongs to a cell")
        umax = np.linalg.norm(u, axis=1).max()
        check(abs(umax / f.attrs["target"] - 1) <= 1.01e-3, f"max|u| {umax:.6f} hits target {f.attrs['target']}")
        check(abs(umax - f.attrs["max_displacement"]) < 1e-12, "recorded max|u| matches the field")
        r = np.linalg.norm(nodes, axis=1)
        check(r.max() <= 1 + 1e-9, "nodes inside the unit disk")
        clamped = np.linalg.norm(nodes - np.array([1.0, 0.0]), axis=1) <= 0.5 - 1e-9
        check(np.abs(u[clamped & (r > 1 - 1e-9)]).max() == 0.0, "u = 0 on the Dirichlet patch")
        check("neo_hookean" in f["inputs/scene"][()].decode(), "scene stored with the result")

print("all checks passed" if not checks.failures else f"{checks.failures} checks failed")
sys.exit(1 if checks.failures else 0)
