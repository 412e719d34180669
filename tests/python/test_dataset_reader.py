"""scripts/hypershape_data.py and scripts/hypershape_torch.py on datasets made by
`hypershape generate` (a 2D one, a 3D one, and one with failed shapes and load cases):
  - every sample reads, with the shapes and dtypes the manifest and config imply, counts agree
    with manifest.json, failed load cases / shapes are skipped by default and served on request;
  - the stored grid is in 'ij' order over x_i = -1 + 2 i / (N - 1): grid_to_mesh of the grid
    SDF and displacement lands on the point-cloud values; the grid traction is the Gaussian;
  - rel_l2 / rel_h1 (the paper's discrete norms) against hand computations, exact gradients of
    linear (P1) and quadratic (P2) fields, grid_to_mesh exact for linear functions;
  - the torch Datasets through DataLoaders (0 and 2 workers), normalisation from stats.json;
  - `check` passes on a good dataset (2D and 3D: no NaN attribute either) and fails after one
    byte of a shard is changed, with a NaN in an array, or a NaN in an attribute.
Needs HYPERSHAPE_BIN and HYPERSHAPE_SOURCE_DIR (set by CTest)."""
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile

import h5py
import numpy as np

bin_ = os.environ["HYPERSHAPE_BIN"]
src = os.environ["HYPERSHAPE_SOURCE_DIR"]
script = os.path.join(src, "scripts", "hypershape_data.py")
sys.path.insert(0, os.path.join(src, "scripts"))
import hypershape_data as hd  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import checks  # noqa: E402
from checks import check  # noqa: E402


CONFIGS = {
    # 4 shapes: 2 / 1 / 1 in train / val / test
    "t2d": """preset: random2d_p1
name: t2d
seed: 7
shapes: {count: 4, h: 0.1}
loads: {count: 3}
representations: {grid_size: 16}
split: {train: 0.5, val: 0.25, test: 0.25}
output: {shard_size: 3}
""",
    "t3d": """name: t3d
seed: 7
shapes: {count: 2, dim: 3, base: sphere, steps: [[0.3, 2]], h: 0.3, dirichlet_radius: 0.4}
loads: {count: 2, gamma: 0.1}
representations: {grid_size: 10}
split: {train: 0.5, val: 0.0, test: 0.5}
output: {shard_size: 1}
""",
    # one redraw allowed and a strict neck test: some shapes fail; one load increment and few
    # Newton steps: most load cases fail
    "failing": """preset: random2d_p1
name: failing
seed: 7
shapes: {count: 3, h: 0.1, max_attempts: 1, min_feature_fraction: 0.08}
loads: {count: 4}
representations: {grid_size: 8}
output: {shard_size: 2}
solver: {max_newton: 8, max_increments: 1}
""",
}


def generate(work, name):
    cfg = os.path.join(work, name + ".yaml")
    with open(cfg, "w") as f:
        f.write(CONFIGS[name])
    out = os.path.join(work, name)
    r = subprocess.run([bin_, "-q", "generate", cfg, "-o", out, "--progress", "0"], capture_output=True, text=True)
    ok = os.path.exists(os.path.join(out, "manifest.json"))
    check(ok, f"generate {name} (exit {r.returncode}){'' if ok else ': ' + r.stdout + r.stderr}")
    return out if ok else None


def read_everything(path, grid_size):
    """Every sample against the manifest: shapes, dtypes, counts, failure semantics."""
    ds = hd.open_dataset(path)
    m = ds.manifest
    d, L, N = m["dim"], m["load_cases_per_shape"], grid_size
    check(ds.dim == d and ds.n_loads == L and ds.n_shapes == m["n_shapes"] and ds.grid_size == N,
          f"{ds.name}: dim {d}, {ds.n_shapes} shapes x {L} loads, grid {ds.grid_size} (config {N})")
    problems, n_conv, n_all, per_shard = [], 0, 0, {}
    for s in ds.samples(include_failed=True):
        n_all += 1
        key = f"({s.shape_id}, {s.load_id})"
        shard = s.shape_id // ds.shard_size
        per_shard.setdefault(shard, [0, 0])
        per_shard[shard][0 if s.status == 1 else 1] += 1
        if s.status == 1:
            n_conv += 1
        if s.nodes is None:  # a failed shape
            if s.status != 0 or not s.reason.startswith("shape failed") or s.shape_id not in ds.failed_shapes:
                problems.append(f"{key}: failed shape served wrongly: {s}")
            continue
        n = len(s.nodes)
        k = s.cells.shape[1]
        want = {
            "nodes": ((n, d), np.float64), "cells": ((s.cells.shape[0], k), np.int64),
            "dirichlet_mask": ((n,), np.bool_), "neumann_mask": ((n,), np.bool_),
            "displacement": ((n, d), np.float64),
            "pc sdf": ((n,), np.float64), "pc dirichlet_distance": ((n,), np.float64),
            "pc traction": ((n, d), np.float64),
            "grid sdf": ((N,) * d, np.float32), "grid dirichlet_distance": ((N,) * d, np.float32),
            "grid inside": ((N,) * d, np.bool_), "grid traction": ((N,) * d + (d,), np.float32),
            "grid displacement": ((N,) * d + (d,), np.float32),
            "p_n": ((d,), np.float64), "g": ((d,), np.float64),
        }
        for name, (shape, dtype) in want.items():
            if name.startswith("pc "):
                a = s.point_cloud.get(name[3:])
            elif name.startswith("grid "):
                a = s.grid.get(name[5:])
            else:
                a = getattr(s, name)
            if a is None or a.shape != shape or a.dtype != dtype:
                problems.append(f"{key} {name}: {None if a is None else (a.shape, a.dtype)}, want {shape} {dtype}")
            elif a.dtype.kind == "f" and not np.isfinite(a).all():
                problems.append(f"{key} {name}: not finite")
        if k not in ((3, 6) if d == 2 else (4, 10)) or s.cells.min() < 0 or s.cells.max() >= n:
            problems.append(f"{key}: cells {s.cells.shape} ids in [{s.cells.min()}, {s.cells.max()}] for {n} nodes")
        if s.status == 1:
            umax = np.linalg.norm(s.displacement, axis=1).max()
            if abs(umax - s.max_displacement) > 1e-12 or abs(umax / s.target - 1) > 1.01e-3:
                problems.append(f"{key}: max|u| {umax} recorded {s.max_displacement} target {s.target}")
            if np.abs(s.displacement[s.dirichlet_mask]).max() != 0:
                problems.append(f"{key}: u != 0 on the Dirichlet patch")
            if s.reason != "target reached" or not s.alpha > 0:
                problems.append(f"{key}: converged with reason {s.reason!r}, alpha {s.alpha}")
        else:
            if not s.reason or s.reason == "target reached":
                problems.append(f"{key}: failed without a reason")
            if s.displacement.any() or s.grid["displacement"].any() or s.alpha != 0:
                problems.append(f"{key}: failed load case stores a displacement or alpha")
    check(not problems, f"{ds.name}: {n_all} samples read, shapes and dtypes as the manifest implies"
          + ("" if not problems else ":\n    " + "\n    ".join(problems[:10])))
    t = m["totals"]
    check(n_all == ds.n_shapes * L and n_conv == t["load_cases_converged"]
          and n_all - n_conv == t["load_cases_failed"],
          f"{ds.name}: {n_conv} converged / {n_all - n_conv} failed, manifest {t['load_cases_converged']} / {t['load_cases_failed']}")
    check(all(per_shard.get(e["index"], [0, 0]) == [e["load_cases_converged"], e["load_cases_failed"]]
              for e in m["shards"]), f"{ds.name}: per-shard counts match the manifest")
    default = ds.keys()
    check(len(default) == n_conv and len(list(ds.samples(grid=False))) == n_conv
          and all(ds.load_status(sid)[lid] == 1 for sid, lid in default),
          f"{ds.name}: by default only the {n_conv} converged load cases are served")
    in_splits = sorted(i for sp in hd.SPLITS for i in ds.shape_ids(sp))
    check(in_splits == ds.shape_ids() and not set(in_splits) & set(ds.failed_shapes)
          and sum(len(ds.keys(sp)) for sp in hd.SPLITS) == n_conv,
          f"{ds.name}: the splits partition the {len(in_splits)} good shapes "
          f"({', '.join(f'{sp} {len(ds.shape_ids(sp))}' for sp in hd.SPLITS)})")
    ds.close()


def grid_consistency(ds):
    """The stored grid is in 'ij' order over [-1, 1]^d: interpolated to the nodes it agrees with
    the point-cloud values; the traction grid is alpha g phi(x - p_N) / I_N everywhere."""
    gamma = ds.config["loads"]["gamma"] if ds.config and "gamma" in ds.config.get("loads", {}) else 0.2
    N, d = ds.grid_size, ds.dim
    h = 2 / (N - 1)
    P = hd.grid_points(d, N).reshape(-1, d)
    worst_sdf = worst_u = worst_t = 0.0
    for s in ds.samples():
        worst_sdf = max(worst_sdf, np.abs(hd.grid_to_mesh(s.grid["sdf"], s.nodes) - s.point_cloud["sdf"]).max())
        worst_u = max(worst_u, hd.rel_l2(s.displacement, hd.grid_to_mesh(s.grid["displacement"], s.nodes)))
        phi = np.exp(-np.sum((P - s.p_n) ** 2, axis=1) / (2 * gamma ** 2))
        t = (s.alpha * phi / s.traction_normaliser)[:, None] * s.g
        worst_t = max(worst_t, np.abs(t - s.grid["traction"].reshape(-1, d)).max() / np.abs(t).max())
        tn = np.exp(-np.sum((s.nodes - s.p_n) ** 2, axis=1) / (2 * gamma ** 2))
        tn = (s.alpha * tn / s.traction_normaliser)[:, None] * s.g * s.neumann_mask[:, None]
        worst_t = max(worst_t, np.abs(tn - s.point_cloud["traction"]).max() / np.abs(tn).max())
        if not np.array_equal(s.grid["inside"], s.grid["sdf"] <= 0):
            worst_sdf = np.inf
    ds.close()
    check(worst_sdf < h, f"{ds.name}: grid SDF at the nodes within {worst_sdf:.3g} of the point-cloud SDF "
          f"(< grid step {h:.3g}); inside == (sdf <= 0)")
    check(worst_u < 0.1, f"{ds.name}: grid displacement at the nodes: rel L2 {worst_u:.3g} from the nodal one")
    check(worst_t < 1e-6, f"{ds.name}: grid and node traction are alpha g phi / I_N (rel. {worst_t:.1e})")


def p2_from_p1(nodes, cells):
    """P2 nodes/cells (VTK order) from a P1 mesh: edge midpoints appended."""
    d = nodes.shape[1]
    edges = hd._P2_EDGES[d]
    mid, extra = {}, []
    out = np.empty((len(cells), d + 1 + len(edges)), np.int64)
    out[:, : d + 1] = cells
    for c, cell in enumerate(cells):
        for e, (a, b) in enumerate(edges):
            key = (min(cell[a], cell[b]), max(cell[a], cell[b]))
            if key not in mid:
                mid[key] = len(nodes) + len(extra)
                extra.append(0.5 * (nodes[key[0]] + nodes[key[1]]))
            out[c, d + 1 + e] = mid[key]
    return np.vstack([nodes, np.array(extra)]), out


def metrics(ds):
    rng = np.random.default_rng(3)
    s = next(ds.samples())
    u, x, cells, d = s.displacement, s.nodes, s.cells, ds.dim
    n = len(x)
    check(hd.rel_l2(u, u) == 0 and hd.rel_h1(u, u, x, cells) == 0, f"{ds.name}: rel_l2(u, u) = rel_h1(u, u) = 0")
    # relative L2 by hand: one node moved by delta; and a uniform scaling
    delta = np.array([0.01, -0.02, 0.03][:d])
    u_hat = u.copy()
    u_hat[n // 2] += delta
    hand = math.sqrt(sum(float(v) ** 2 for v in delta) / n) / math.sqrt(sum(float(v) ** 2 for v in u.ravel()) / n)
    r = hd.rel_l2(u, u_hat)
    check(abs(r - hand) <= 1e-12 * hand, f"{ds.name}: rel_l2 of one moved node {r:.12g} = hand {hand:.12g}")
    check(abs(hd.rel_l2(u, 1.1 * u) - 0.1) < 1e-12, f"{ds.name}: rel_l2(u, 1.1 u) = 0.1")
    batch = hd.rel_l2(np.stack([u, u]), np.stack([u_hat, 1.1 * u]))
    check(np.allclose(batch, [hand, 0.1], rtol=1e-12), f"{ds.name}: rel_l2 over a batch axis")
    # relative H1 of a linear difference: the gradient is exactly A at every node
    A, b = rng.normal(size=(d, d)), rng.normal(size=d)
    e = x @ A.T + b
    G = hd.nodal_gradient(e, x, cells)
    check(np.abs(G - A).max() < 1e-10, f"{ds.name}: P1 nodal gradient of a linear field is exact ({np.abs(G - A).max():.1e})")
    norm_e = math.sqrt(np.mean(np.sum(e * e, axis=1)) + np.sum(A * A))
    check(abs(hd.norm_h1(e, x, cells) - norm_e) < 1e-12 * norm_e,
          f"{ds.name}: ||A x + b||_H1_N = sqrt(mean|A x + b|^2 + |A|_F^2) = {norm_e:.10g}")
    r = hd.rel_h1(u, u + e, x, cells)
    want = norm_e / hd.norm_h1(u, x, cells)
    check(abs(r - want) < 1e-12 * want, f"{ds.name}: rel_h1(u, u + A x + b) = {r:.10g} = exact {want:.10g}")
    # P2: the gradient of a quadratic field is exact at every node
    x2, c2 = p2_from_p1(x, cells)
    Q = rng.normal(size=(d, d))
    f = np.einsum("ni,ij,nj->n", x2, Q, x2) + x2 @ b
    g = hd.nodal_gradient(f, x2, c2)
    exact = x2 @ (Q + Q.T).T + b
    check(np.abs(g - exact).max() < 1e-9, f"{ds.name}: P2 nodal gradient of a quadratic field is exact "
          f"({np.abs(g - exact).max():.1e})")
    # grid_to_mesh reproduces linear functions at the mesh points
    N = ds.grid_size
    P = hd.grid_points(d, N)
    check(np.allclose(P[(1,) * d], hd.grid_axis(N)[1]) and P[(0,) * d].tolist() == [-1.0] * d
          and P[(N - 1,) * d].tolist() == [1.0] * d and P[(1,) + (0,) * (d - 1)][0] > -1,
          f"{ds.name}: grid_points in 'ij' order, x_i = -1 + 2 i / (N - 1)")
    lin = P @ A.T + b  # (N..., d)
    err = np.abs(hd.grid_to_mesh(lin, x) - (x @ A.T + b)).max()
    err1 = np.abs(hd.grid_to_mesh(P[..., 0] * 2 - 1, x) - (x[:, 0] * 2 - 1)).max()
    check(err < 1e-12 and err1 < 1e-12, f"{ds.name}: grid_to_mesh exact for linear fields at the mesh points ({err:.1e})")
    ds.close()


def torch_part(paths):
    try:
        import torch
    except ImportError as ex:
        print(f"SKIP torch part: torch cannot be imported ({ex}); install python3-torch")
        return
    import hypershape_torch as ht
    torch.manual_seed(0)
    for path in paths:
        ds = hd.open_dataset(path)
        d, N = ds.dim, ds.grid_size
        ds.close()
        for split in hd.SPLITS:
            g = ht.GridDataset(path, split)
            want = len(hd.open_dataset(path).keys(split))
            check(len(g) == want, f"{ds.name} {split}: GridDataset has the {want} converged load cases")
        g = ht.GridDataset(path, "train", normalize="channelwise")
        for workers in (0, 2):
            loader = torch.utils.data.DataLoader(g, batch_size=2, shuffle=True, num_workers=workers)
            seen, shapes = [], set()
            for b in loader:
                B = b["x"].shape[0]
                shapes.add((tuple(b["x"].shape[1:]), tuple(b["y"].shape[1:]), tuple(b["inside"].shape[1:]),
                            b["x"].dtype, b["y"].dtype, b["inside"].dtype))
                seen += list(zip(b["shape_id"].tolist(), b["load_id"].tolist()))
                assert B <= 2
            want = {((2 + d,) + (N,) * d, (d,) + (N,) * d, (N,) * d, torch.float32, torch.float32, torch.bool)}
            check(shapes == want and sorted(seen) == sorted(g.keys()),
                  f"{ds.name}: grid batches through a DataLoader ({workers} workers): x (B, {2 + d}, {N}^{d}), "
                  f"y (B, {d}, {N}^{d}), each item once {sorted(shapes, key=str)}")
        # normalisation: stats.json is over the train split, so the train targets come out standard
        ys = torch.stack([g[i]["y"] for i in range(len(g))]).transpose(0, 1).flatten(1).double()
        check(ys.mean(1).abs().max() < 1e-4 and (ys.std(1, unbiased=False) - 1).abs().max() < 1e-4,
              f"{ds.name}: channelwise grid targets over train: mean {ys.mean(1).numpy().round(6)}, "
              f"std {ys.std(1, unbiased=False).numpy().round(6)}")
        raw = ht.GridDataset(path, "train", with_mesh=True, dtype=torch.float64)
        rms = ht.GridDataset(path, "train", normalize="rms")
        it, itn, itr = raw[0], g[0], rms[0]
        check(torch.allclose(g.denormalize(itn["y"]).double(), it["y"], atol=1e-6)
              and torch.allclose(itr["x"][:2].double(), it["x"][:2])
              and torch.allclose(rms.denormalize(itr["y"]).double(), it["y"], atol=1e-6),
              f"{ds.name}: denormalize undoes channelwise and rms; rms leaves the distances alone")
        u_mesh = it["u_mesh"]
        a = ht.grid_to_mesh_torch(it["y"][None], it["nodes"][None])[0]
        b_ = hd.grid_to_mesh(np.moveaxis(it["y"].numpy(), 0, -1), it["nodes"].numpy())
        check(np.abs(a.numpy() - b_).max() < 1e-12 and u_mesh.shape == it["nodes"].shape,
              f"{ds.name}: grid_to_mesh_torch == grid_to_mesh (with_mesh items carry nodes, u_mesh, cells)")
        l_t = ht.rel_l2_loss(a[None], u_mesh[None]).item()
        check(abs(l_t - hd.rel_l2(u_mesh.numpy(), b_)) < 1e-12, f"{ds.name}: rel_l2_loss == rel_l2 ({l_t:.4g})")
        # rel_h1_grid_loss on linear fields: finite differences are exact
        P = torch.as_tensor(hd.grid_points(d, N)).movedim(-1, 0)[None]  # (1, d, N..)
        A, B_ = torch.randn(d, d, dtype=torch.float64), torch.randn(d, d, dtype=torch.float64)
        L1 = torch.einsum("ij,bj...->bi...", A, P) + 1
        L2 = torch.einsum("ij,bj...->bi...", B_, P)
        npts = N ** d
        want = math.sqrt((L2 ** 2).sum().item() + npts * (B_ ** 2).sum().item()) / math.sqrt(
            (L1 ** 2).sum().item() + npts * (A ** 2).sum().item())
        got = ht.rel_h1_grid_loss(L1 + L2, L1).item()
        check(abs(got - want) < 1e-10 * want, f"{ds.name}: rel_h1_grid_loss of a linear difference exact ({got:.8g})")
        # point clouds: variable sizes, padded
        pc = ht.PointCloudDataset(path, "train", normalize="channelwise", with_mesh=True)
        loader = torch.utils.data.DataLoader(pc, batch_size=len(pc), collate_fn=ht.collate_padded, num_workers=0)
        b = next(iter(loader))
        n = b["n_points"]
        n_max = int(n.max())
        items = [pc[i] for i in range(len(pc))]
        ok = (b["pos"].shape == (len(pc), n_max, d) and b["x"].shape == (len(pc), n_max, 2 + d)
              and b["y"].shape == (len(pc), n_max, d) and b["mask"].shape == (len(pc), n_max)
              and b["mask"].sum(1).tolist() == n.tolist() and len(b["cells"]) == len(pc)
              and all(torch.equal(b["pos"][i, : n[i]], items[i]["pos"]) for i in range(len(pc)))
              and not b["x"][~b["mask"]].any())
        check(ok, f"{ds.name}: point-cloud batch: pos (B, n_max, {d}), x (B, n_max, {2 + d}), y (B, n_max, {d}), "
              f"mask; point counts {sorted(set(n.tolist()))}")
        ys = torch.cat([it["y"] for it in items]).double()
        check(ys.mean(0).abs().max() < 1e-4 and (ys.std(0, unbiased=False) - 1).abs().max() < 1e-4,
              f"{ds.name}: channelwise point-cloud targets over train are standardised")
        loader = torch.utils.data.DataLoader(ht.PointCloudDataset(path, "test"), batch_size=1, num_workers=2)
        got = [(int(b["shape_id"]), int(b["load_id"]), tuple(b["x"].shape)) for b in loader]
        check(len(got) == len(hd.open_dataset(path).keys("test")) and all(s[2][2] == 2 + d for s in got),
              f"{ds.name}: point clouds of the test split through 2 workers, batch_size 1")


def cli(path, work):
    r = subprocess.run([sys.executable, script, "summary", path], capture_output=True, text=True)
    check(r.returncode == 0 and "load cases" in r.stdout and "loads/displacement" in r.stdout
          and "grid_displacement" in r.stdout, f"summary exits 0 and lists counts, stats and arrays (exit {r.returncode})")
    r = subprocess.run([sys.executable, script, "check", path], capture_output=True, text=True)
    check(r.returncode == 0, f"check passes on the good dataset: {r.stdout.strip().splitlines()[-1] if r.stdout else r.stderr}")
    bad = os.path.join(work, "corrupt")
    shutil.copytree(path, bad)
    shard = os.path.join(bad, json.load(open(os.path.join(bad, "manifest.json")))["shards"][-1]["file"])
    size = os.path.getsize(shard)
    with open(shard, "r+b") as f:
        f.seek(size // 2)
        byte = f.read(1)
        f.seek(size // 2)
        f.write(bytes([byte[0] ^ 0x01]))
    r = subprocess.run([sys.executable, script, "check", bad], capture_output=True, text=True)
    check(r.returncode != 0 and os.path.basename(shard) in r.stdout,
          f"check fails after one byte of {os.path.basename(shard)} is flipped (exit {r.returncode}): "
          + " | ".join(l for l in r.stdout.splitlines() if l.startswith("FAIL"))[:300])
    first = os.path.join(bad, json.load(open(os.path.join(bad, "manifest.json")))["shards"][0]["file"])
    with h5py.File(first, "r+") as f:
        g = next(g for g in f["shapes"].values() if "loads" in g)
        g["loads/grid_displacement"][0, 1, 1, 0] = np.nan
    r = subprocess.run([sys.executable, script, "check", bad], capture_output=True, text=True)
    check(r.returncode != 0 and "grid_displacement: 1 NaN/Inf" in r.stdout, "check names an array holding a NaN")
    with h5py.File(first, "r+") as f:  # 3D shards once carried isoperimetric_ratio = NaN
        next(iter(f["shapes"].values())).attrs["isoperimetric_ratio"] = np.nan
    r = subprocess.run([sys.executable, script, "check", bad], capture_output=True, text=True)
    check(r.returncode != 0 and "@isoperimetric_ratio: NaN/Inf attribute" in r.stdout,
          "check names an attribute holding a NaN")
    os.remove(first)
    r = subprocess.run([sys.executable, script, "check", bad], capture_output=True, text=True)
    check(r.returncode != 0 and "missing" in r.stdout, "check fails when a shard is missing")


def solver_outcomes(path):
    """solver_report's split by outcome adds up, and load_case_outcome reads the solver's reasons
    (their wording is checked against the C++ that writes them)."""
    r = hd.solver_report(path)
    by = r["by_outcome"]
    check(sum(v["load_cases"] for v in by.values()) == r["load_cases"]
          and sum(by.get(o, {"load_cases": 0})["load_cases"] for o in ("failed", "failed at a verified fold", "shape failed"))
          == r["load_cases"] - r["converged"]
          and r["verified_folds"] == by.get("failed at a verified fold", {"load_cases": 0})["load_cases"]
          and by.get("shape failed", {"newton_iterations": 0})["newton_iterations"] == 0
          and sum(v["newton_iterations"] for v in by.values()) == r["newton_iterations"]["total"],
          f"solver report by outcome adds up to the load cases, failures and Newton iterations: {by}")
    reasons = {
        (1, "target reached"): "path",
        (1, "target reached after a branch switch (loss of stability at max|u| = 0.27, alpha = 24.4: "
            "the tangent has 1 negative eigenvalue(s) (buckling or a bifurcation))"): "branch switch from an unstable state",
        (1, "target reached after a branch switch (fold: max|u| = target lies on an unstable segment of "
            "the path (...))"): "branch switch from an unstable state",
        (1, "target reached after a branch switch (increment below minimum or too many increments (last: "
            "no progress in 4 Newton iterations))"): "branch switch after a stall",
        (1, "target reached by arc-length continuation (before: Newton budget of 200 iterations spent)"):
            "arc-length rescue",
        (1, "target reached from rest without the first-increment hint (first try: Newton budget of 200 "
            "iterations spent)"): "retry from rest",
        (1, "target reached from the P1 solution on the same mesh (target reached after a branch switch "
            "(...); first try: ...)"): "from the P1 solution",
        (1, "target reached by load control (displacement control: ...)"): "other",
        (0, "target reached"): "failed",
        (0, "fold: max|u| = target lies on an unstable segment of the path (at max|u| = 0.46, ...)"):
            "failed at a verified fold",
        (0, "Newton budget of 200 iterations spent (after a branch switch from: fold: max|u| = ...)"): "failed",
    }
    got = {k: hd.load_case_outcome(*k) for k in reasons}
    check(got == reasons, f"load_case_outcome classes the solver's reasons: {got}")
    cpp = "".join(open(os.path.join(src, "src", "solver", f)).read()
                  for f in ("branch_switch.cpp", "path_following.cpp", "nonlinear.cpp"))
    cpp += open(os.path.join(src, "src", "factory", "p1_start.cpp")).read()
    written = ['"target reached after a branch switch ("', '"loss of stability at max|u| = "',
               '"fold: max|u| = target lies on an unstable segment', '"target reached by arc-length continuation',
               '"target reached from rest without the first-increment hint', '"target reached"',
               '"target reached from the P1 solution on the same mesh']
    check(all(w in cpp for w in written), "the reasons load_case_outcome reads are the ones src/solver writes")
    out = subprocess.run([sys.executable, script, "solver", path], capture_output=True, text=True).stdout
    check("by outcome (load cases, Newton iterations each): path " in out, "`solver` prints the split by outcome")


with tempfile.TemporaryDirectory() as work:
    paths = {name: generate(work, name) for name in CONFIGS}
    if all(paths.values()):
        for name, N in (("t2d", 16), ("t3d", 10), ("failing", 8)):
            read_everything(paths[name], N)
        f = hd.open_dataset(paths["failing"])
        t = f.manifest["totals"]
        print(f"note: the failing dataset has {t['shapes_failed']} failed shapes, "
              f"{t['load_cases_failed']} failed and {t['load_cases_converged']} converged load cases")
        check(t["load_cases_failed"] > 0, "the failing dataset has failed load cases to skip")
        for name in ("t2d", "t3d"):
            grid_consistency(hd.open_dataset(paths[name]))
            metrics(hd.open_dataset(paths[name]))
        torch_part([paths["t2d"], paths["t3d"]])
        cli(paths["t2d"], work)
        for name in ("t2d", "failing"):
            solver_outcomes(paths[name])
        r = subprocess.run([sys.executable, script, "check", paths["t3d"]], capture_output=True, text=True)
        with h5py.File(os.path.join(paths["t3d"], "shards", "shard-000000.h5")) as f:
            iso = [g.attrs["isoperimetric_ratio"] for g in f["shapes"].values()]
        check(r.returncode == 0 and all(0 < v <= 1 for v in iso),
              f"3D: check passes, every attribute finite (isoperimetric ratio 36 pi V^2 / S^3 = {iso})")

print("all checks passed" if not checks.failures else f"{checks.failures} checks failed")
sys.exit(1 if checks.failures else 0)
