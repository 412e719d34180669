"""`hypershape generate --preset NAME --mini` and `scripts/hypershape_data.py plot`:
  - the mini Random2D: named random2d_mini, 4 shapes x 2 load cases, 32^2 grids, and its shape 0
    is the preset's shape 0 (`hypershape shapes` of the full preset: the same mesh);
  - bad input stops with exit code 2 and names the option: an unknown preset, --preset with a
    config file, plot --shape of no solved shape, plot --load out of range;
  - plot writes a PNG of each 2D and 3D gallery; the pieces it draws: P2 triangles split in four
    cover the same area, the boundary it draws has the shape's stored boundary measure
    (perimeter in 2D, surface area in 3D, to 1e-9), the patch is the Dirichlet nodes, and the
    colour of the 2D panel is |u| of the load case.
Needs HYPERSHAPE_BIN and HYPERSHAPE_SOURCE_DIR (set by CTest)."""
import os
import shutil
import subprocess
import sys
import tempfile

import h5py
import numpy as np

src = os.environ["HYPERSHAPE_SOURCE_DIR"]
bin_ = os.environ["HYPERSHAPE_BIN"]
sys.path.insert(0, os.path.join(src, "scripts"))
import hypershape_data as hd  # noqa: E402
import hypershape_plot as hp  # noqa: E402

script = os.path.join(src, "scripts", "hypershape_data.py")
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import checks  # noqa: E402
from checks import check  # noqa: E402


def run(*args):
    return subprocess.run(list(args), capture_output=True, text=True)


def check_bad_input(tmp, d):
    cases = [([bin_, "generate", "--preset", "nope", "--mini", "-o", f"{tmp}/bad"], "unknown preset 'nope'"),
             ([bin_, "generate", f"{src}/tests/cli/expected/preset_r2.yaml", "--preset", "random2d"], "--preset"),
             (["/usr/bin/python3", script, "plot", d, "--shape", "99"], "--shape [99]"),
             (["/usr/bin/python3", script, "plot", d, "--load", "2"], "--load [2]")]
    for args, key in cases:
        r = run(*args)
        check(r.returncode == 2 and key in r.stderr, f"{' '.join(args[1:3] + args[-2:])}: exit {r.returncode}, "
                                                     f"names {key!r}: {r.stderr.strip()[:100]!r}")
    check(not os.path.exists(f"{tmp}/bad"), "nothing written for the unknown preset")


def check_mini(tmp):
    d = f"{tmp}/mini2d"
    r = run(bin_, "-q", "generate", "--preset", "random2d", "--mini", "--progress", "0", "-o", d)
    if not check(r.returncode == 0, f"generate --preset random2d --mini: exit {r.returncode} {r.stderr[-200:]}"):
        return None
    ds = hd.open_dataset(d)
    s = ds.sample(0, 0)
    check((ds.name, ds.n_shapes, ds.n_loads, s.grid["sdf"].shape) == ("random2d_mini", 4, 2, (32, 32)),
          f"mini: {ds.name}, {ds.n_shapes} shapes x {ds.n_loads} load cases, grid {s.grid['sdf'].shape}")
    r = run(bin_, "-q", "shapes", f"{src}/configs/presets/random2d.yaml", "-n", "1", "-o", f"{tmp}/full.h5")
    with h5py.File(f"{tmp}/full.h5") as a, h5py.File(f"{d}/shards/shard-000000.h5") as b:
        same = np.array_equal(a["shapes/000000/mesh/nodes"][()], b["shapes/000000/mesh/nodes"][()])
    check(r.returncode == 0 and same, "mini shape 0 == the full preset's shape 0 (same mesh)")
    return d


def _areas(x, t):
    e1, e2 = x[t[:, 1]] - x[t[:, 0]], x[t[:, 2]] - x[t[:, 0]]
    c = np.cross(e1, e2)
    return 0.5 * (np.abs(c) if c.ndim == 1 else np.linalg.norm(c, axis=1))


def check_pieces(d, dim):
    ds = hd.open_dataset(d)
    s = ds.sample(ds.shape_ids()[0], 0, grid=False)
    x = s.nodes
    # What is coloured: the cells (2D) / the boundary triangles (3D), P2 ones split in four.
    whole = hp._corners(s.cells, 2) if dim == 2 else hp._boundary(s.cells, 3)
    split = hp._split_p2(whole, hp._edge_midpoints(s.cells, dim))
    p2 = s.cells.shape[1] in (6, 10)
    check(len(split) == (4 if p2 else 1) * len(whole) and abs(_areas(x, split).sum() / _areas(x, whole).sum() - 1) < 1e-12,
          f"{d}: {len(split)} drawn triangles ({'P2 split' if p2 else 'P1'}) cover the same area")
    if dim == 2:
        edges = hp._boundary(s.cells, 2)
        measure = np.linalg.norm(x[edges[:, 1]] - x[edges[:, 0]], axis=1).sum()
    else:
        measure = _areas(x, whole).sum()
    want = ds.shape(s.shape_id).attrs["boundary_measure"]
    check(abs(measure / want - 1) < 1e-9, f"{d}: drawn boundary measure {measure:.6f} == stored {want:.6f}")
    patch = np.unique(hp._boundary(s.cells, dim)[s.dirichlet_mask[hp._boundary(s.cells, dim)].all(axis=1)])
    check(set(patch.tolist()) <= set(np.flatnonzero(s.dirichlet_mask).tolist()) and len(patch) > 0,
          f"{d}: the patch drawn: {len(patch)} boundary vertices, all on the Dirichlet patch")


def check_colours(d):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    ds = hd.open_dataset(d)
    s = ds.sample(1, 1, grid=False)
    fig, ax = plt.subplots()
    art = hp.draw_2d(ax, s)
    check(np.allclose(np.asarray(art.get_array()), np.linalg.norm(s.displacement, axis=1)),
          "2D panel: the colour is |u| of load case 1 at the nodes")
    check(len(hp._loads(s)) == 1 and np.allclose(hp._loads(s)[0][0], s.p_n), "2D panel: the load drawn at p_N")
    plt.close(fig)


def check_png(d, tmp, name):
    out = f"{tmp}/{name}.png"
    r = run("/usr/bin/python3", script, "plot", d, "--gallery", "4", "-o", out)
    ok = r.returncode == 0 and os.path.exists(out) and open(out, "rb").read(8) == b"\x89PNG\r\n\x1a\n"
    check(ok and os.path.getsize(out) > 20000, f"plot --gallery 4 {name}: {r.stdout.strip()} "
                                               f"({os.path.getsize(out) if ok else 0} bytes) {r.stderr[-300:]}")


def check_tail(d):
    """scripts/stability_tail.py on the mini: its tail (above 3x the median Newton iterations) and
    its bins by the distance of p_N to the patch, against the same counted from the arrays here."""
    r = run("/usr/bin/python3", os.path.join(src, "scripts", "stability_tail.py"), d)
    its, dist = [], []
    for shard in sorted(os.listdir(os.path.join(d, "shards"))):
        with h5py.File(os.path.join(d, "shards", shard)) as h:
            for g in h["shapes"].values():
                p_d, rad = np.asarray(g.attrs["dirichlet_center"])[:2], g.attrs["dirichlet_radius"]
                its += list(g["loads"]["newton_iterations"][()])
                dist += [np.linalg.norm(p[:2] - p_d) - rad for p in g["loads"]["p_n"][()]]
    its, dist = np.array(its, float), np.array(dist)
    tail = int((its > 3 * np.median(its)).sum())
    near = int((dist < 0.1).sum())
    head = f"{len(its)} load cases: Newton its median {np.median(its):g}"
    ok = r.returncode == 0 and r.stdout.startswith(head) and f"{tail} (" in r.stdout.splitlines()[0] and \
        f"p_N to the patch [-9, 0.1): {near} load cases" in r.stdout
    check(ok, f"stability_tail.py: {len(its)} load cases, {tail} in the tail, {near} with p_N within 0.1 of the patch "
              f"{r.stdout.splitlines()[:1]} {r.stderr[-200:]}")


def main():
    tmp = tempfile.mkdtemp()
    try:
        d2 = check_mini(tmp)
        if d2:
            check_bad_input(tmp, d2)
            check_pieces(d2, 2)
            check_colours(d2)
            check_png(d2, tmp, "mini2d")
            check_tail(d2)
        cfg = f"{tmp}/p3.yaml"
        open(cfg, "w").write("preset: random3d\nname: p3\nseed: 7\nshapes: {count: 1}\nloads: {count: 2}\n"
                             "representations: {grid_size: 8}\n")
        d3 = f"{tmp}/p3"
        if check(run(bin_, "-q", "generate", cfg, "--progress", "0", "-o", d3).returncode == 0, "3D dataset"):
            check_pieces(d3, 3)
            check_png(d3, tmp, "p3")
    finally:
        shutil.rmtree(tmp)
    print(f"{'ok' if checks.failures == 0 else 'FAILED'}: {checks.failures} failures")
    return 1 if checks.failures else 0


if __name__ == "__main__":
    sys.exit(main())
