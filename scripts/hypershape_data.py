#!/usr/bin/python3
"""Reader, metrics and checks for the dataset directories written by `hypershape generate`.

Needs only numpy and h5py (Debian's python3-numpy, python3-h5py); PyYAML is used to parse
dataset.yaml when it is importable. The PyTorch Datasets live in scripts/hypershape_torch.py.
The layout of a dataset directory is documented in docs/FORMAT.md ("Datasets").

Library:

    import sys; sys.path.insert(0, "scripts")
    import hypershape_data as hd

    ds = hd.open_dataset("/tmp/pyds")        # manifest, splits, stats, config; no shard opened yet
    ds.keys("train")                          # [(shape_id, load_id), ...] converged load cases
    s = ds.sample(0, 3)                       # one Sample (arrays read from its shard on demand)
    for s in ds.samples("test"): ...          # every converged load case of the test shapes
    u_hat = hd.grid_to_mesh(s.grid["displacement"], s.nodes)       # grid -> mesh points
    hd.rel_l2(s.displacement, u_hat), hd.rel_h1(s.displacement, u_hat, s.nodes, s.cells)

Command line:

    scripts/hypershape_data.py summary DIR   # counts, splits, statistics, every array's shape
    scripts/hypershape_data.py check DIR     # CRC-32 of every shard against manifest.json, no
                                             # NaN/Inf in any stored array; exit 1 otherwise
    scripts/hypershape_data.py plot DIR [--shape I ...] [--load J ...] [-o file.png]
                                             # deformed shapes coloured by |u| (matplotlib,
                                             # scripts/hypershape_plot.py)

Handles: a Dataset opens one h5py.File per shard, read-only, the first time a shard is read,
and keeps it until close(). Handles are never shared across processes: a Dataset that finds
itself in another process (a forked DataLoader worker) drops the handles it inherited and
opens its own, and a pickled Dataset carries no handles.
"""
import argparse
import json
import math
import os
import re
import sys
import zlib
from collections import OrderedDict

import h5py
import numpy as np

__all__ = [
    "open_dataset", "Dataset", "Shape", "Sample", "rel_l2", "rel_h1", "norm_l2", "norm_h1",
    "nodal_gradient", "shape_error_estimates", "error_estimates", "grid_axis", "grid_points", "grid_to_mesh", "check_dataset", "summary",
]

SPLITS = ("train", "val", "test")


def _text(v):
    """An HDF5 string (attribute or dataset element) as str."""
    if isinstance(v, bytes):
        return v.decode("utf-8", "replace")
    if isinstance(v, np.ndarray) and v.shape == ():
        return _text(v[()])
    return str(v)


# ---------------------------------------------------------------------------------------------
# Records
# ---------------------------------------------------------------------------------------------

class Shape:
    """One shape of a dataset: geometry and per-shape representations (read when first used).

    Attributes (None where the shape failed or the representation was not stored; n nodes,
    m cells, k nodes per cell: 3 / 6 (P1 / P2 triangles), 4 / 10 (P1 / P2 tetrahedra), N grid
    points per axis, d the dimension, L load cases per shape):
      shape_id (int), ok (bool), failure (str, "" if ok), dim (int)
      attrs           dict of the group's attributes: shape metrics (measure, isoperimetric_ratio,
                      hausdorff_to_base, mesh_min_angle_deg, ...), dirichlet_center, dirichlet_radius,
                      source_file (str; directory families such as Liver: the shape's surface file)
      nodes           (n, d) float64   FE nodes (vertices first, then P2 edge midpoints), length
      cells           (m, k) int64     node ids per cell, VTK order
      dirichlet_mask  (n,) bool        node on the Dirichlet patch (u = 0)
      neumann_mask    (n,) bool        node on the Neumann boundary
      point_cloud     dict: sdf (n,) float64, dirichlet_distance (n,) float64
      grid            dict: sdf (N,)*d float32, dirichlet_distance (N,)*d float32, inside (N,)*d bool
      boundary_points (b, d) float64, boundary_facets (f, d) int32: the boundary polygon/surface
      status          (L,) int8        1 converged, 0 failed (all 0 for a failed shape)
      reasons         list of L str    solver's outcome per load case
    """

    def __init__(self, dataset, shape_id):
        self._ds = dataset
        self.shape_id = int(shape_id)
        self.dim = dataset.dim
        g = dataset._group(self.shape_id)
        self.attrs = {k: (_text(v) if isinstance(v, (bytes, np.bytes_)) else v) for k, v in g.attrs.items()}
        self.ok = self.attrs.get("status", "ok") == "ok"
        self.failure = self.attrs.get("failure", "") if not self.ok else ""
        L = dataset.n_loads
        self.nodes = self.cells = self.dirichlet_mask = self.neumann_mask = None
        self.boundary_points = self.boundary_facets = None
        self.point_cloud, self.grid = {}, {}
        if not self.ok:
            self.status = np.zeros(L, np.int8)
            self.reasons = [f"shape failed: {self.failure}"] * L
            return
        self.nodes = g["nodes"][...]
        self.cells = g["cells"][...]
        self.dirichlet_mask = g["dirichlet_mask"][...].astype(bool)
        self.neumann_mask = g["neumann_mask"][...].astype(bool)
        if "boundary" in g:
            self.boundary_points = g["boundary/points"][...]
            self.boundary_facets = g["boundary/facets"][...]
        if "point_cloud" in g:
            self.point_cloud = {k: g["point_cloud"][k][...] for k in g["point_cloud"]}
        if "grid" in g:
            self.grid = {k: g["grid"][k][...] for k in g["grid"]}
            if "inside" in self.grid:
                self.grid["inside"] = self.grid["inside"].astype(bool)
        self.status = g["loads/status"][...]
        self.reasons = [_text(r) for r in g["loads/reason"][...]]
        # Drawn scene parameters: "<effect label>/<key>" -> (1,) per shape or (L,) per load case
        # (placements of further tractions: (L, d)).
        self.params = {}
        if "params" in g:
            g["params"].visititems(lambda n, o: self.params.__setitem__(n, o[...])
                                   if isinstance(o, h5py.Dataset) else None)

    @property
    def n_nodes(self):
        return 0 if self.nodes is None else len(self.nodes)

    def __repr__(self):
        if not self.ok:
            return f"Shape({self.shape_id}, failed: {self.failure})"
        return (f"Shape({self.shape_id}, {self.n_nodes} nodes, {len(self.cells)} cells, "
                f"{int(self.status.sum())}/{len(self.status)} load cases converged)")


class Sample:
    """One load case of one shape: inputs and the solution, on the mesh and on the grid.

    Shapes (n nodes, m cells, k nodes per cell, N grid points per axis, d the dimension):
      shape_id, load_id (int); dim (int)
      status (int)        1 converged, 0 failed (fields then all zero, or None for a failed shape)
      reason (str)        the solver's outcome ("target reached", or why it failed)
      nodes (n, d) float64, cells (m, k) int64, dirichlet_mask (n,) bool, neumann_mask (n,) bool
      displacement (n, d) float64      u at the nodes, length
      point_cloud  dict: sdf (n,), dirichlet_distance (n,), traction (n, d): float64; traction is
                   t = alpha g phi(x - p_N) / I_N at the Neumann nodes and zero elsewhere
      grid         dict: sdf, dirichlet_distance, inside (N,)*d (float32, float32, bool);
                   traction, displacement (N,)*d + (d,) float32; numpy 'ij' order, x index first
      alpha, target, max_displacement, min_det_f, traction_normaliser (float)
      p_n (d,), g (d,) float64 (the first traction's; None without one); newton_iterations,
      solves, failed_increments, recovery_iterations (int)
      error_estimate_rel_l2, error_estimate_max_u, error_estimate_alpha (float): the label's own
                   estimated error (relative L2 of u; relative, signed, of max|u| and of alpha;
                   NaN when the dataset has no estimates, 0 for a failed load case, -1 when
                   no estimate could be formed)
      accuracy_level (int): the accuracy ladder's level the label was solved at (a dataset asked
                   for by accuracy; 0 otherwise), carried exactly to the shape's stored mesh
      params       dict: drawn scene parameter "<effect label>/<key>" -> its value for this
                   load case (float, or (d,) for a further traction's centre/direction)
    The input channels the scene's effects bring (Dataset.channels: "traction", "body_force",
    ...) are in point_cloud (n, d) and grid (N,)*d + (d,) under their names.
    Arrays belong to the Sample (per-shape arrays are shared by the samples of one shape: do
    not modify them in place).
    """

    def __init__(self, **kw):
        self.__dict__.update(kw)

    @property
    def n_nodes(self):
        return 0 if self.nodes is None else len(self.nodes)

    def __repr__(self):
        return (f"Sample(shape {self.shape_id}, load {self.load_id}, status {self.status}, "
                f"{self.n_nodes} nodes, target {self.target:.4g}, reason {self.reason!r})")


# Per-load-case arrays under "loads/" with one row per load case.
_LOAD_SCALARS = ("alpha", "target", "max_displacement", "min_det_f", "traction_normaliser",
                 "newton_iterations", "solves", "failed_increments", "recovery_iterations",
                 "error_estimate_rel_l2", "error_estimate_max_u", "error_estimate_alpha", "accuracy_level")
# The a posteriori estimates of each label's own error (docs/ACCURACY.md), per load case.
ERROR_ESTIMATES = ("error_estimate_rel_l2", "error_estimate_max_u", "error_estimate_alpha")
_LOAD_COUNTS = ("newton_iterations", "solves", "failed_increments", "recovery_iterations", "accuracy_level")


class Dataset:
    """A dataset directory. Create with open_dataset(dir).

    Attributes: path, manifest (dict), splits (dict: train/val/test -> sorted shape ids, plus
    seed and fractions), stats (dict, stats.json), config (dict parsed from dataset.yaml, or None
    without PyYAML), config_text (str), name, dim, n_shapes, n_loads (load cases per shape),
    shard_size, grid_size (N, or None if no grid is stored), failed_shapes (list of ids),
    channels (input channels per load case the scene's effects bring, e.g. ["traction",
    "body_force"]: loads/<name> at the nodes, loads/grid_<name> on the grid), scene_text (the
    effects solved, YAML, as stored in the shards).
    """

    def __init__(self, path, cache_shapes=4):
        self.path = os.path.abspath(path)
        mpath = os.path.join(self.path, "manifest.json")
        if not os.path.exists(mpath):
            raise FileNotFoundError(f"{path}: no manifest.json (not a complete dataset; "
                                    "run `hypershape index DIR` after a SLURM array)")
        self.manifest = _read_json(mpath)
        if self.manifest.get("format") != "hypershape-dataset":
            raise ValueError(f"{mpath}: not a hypershape dataset manifest")
        if int(self.manifest.get("format_version", 0)) != 1:
            raise ValueError(f"{mpath}: unsupported format_version {self.manifest.get('format_version')}")
        sp, st = os.path.join(self.path, "splits.json"), os.path.join(self.path, "stats.json")
        self.splits = _read_json(sp) if os.path.exists(sp) else None
        self.stats = _read_json(st) if os.path.exists(st) else None
        cp = os.path.join(self.path, "dataset.yaml")
        self.config_text = open(cp).read() if os.path.exists(cp) else ""
        self.config = None
        try:
            import yaml  # optional
            self.config = yaml.safe_load(self.config_text) if self.config_text else None
        except ImportError:
            pass
        m = self.manifest
        self.name = m["name"]
        self.dim = int(m["dim"])
        self.n_shapes = int(m["n_shapes"])
        self.n_loads = int(m["load_cases_per_shape"])
        self.shard_size = int(m["shard_size"])
        self.complete = bool(m["complete"])
        self.failed_shapes = [int(i) for i in m.get("failed_shapes", [])]
        self._shards = {}  # shape id range per shard
        for e in m["shards"]:
            self._shards[int(e["index"])] = e
        self._cache_size = max(1, int(cache_shapes))
        self._files = {}
        self._pid = os.getpid()
        self._shape_cache = OrderedDict()
        self._status = None  # shape id -> (L,) int8, read on demand
        self.grid_size = None
        self.channels, self.scene_text = [], ""
        self.channel_components = {}  # channel -> components (d for vectors, 1 for pressure, modulus)
        ok = self.shape_ids(include_failed=False)
        if ok:
            g = self._group(ok[0])
            if "grid/sdf" in g:
                self.grid_size = int(g["grid/sdf"].shape[0])
            self.channels = _channels_of(g["loads"])
            self.channel_components = {
                c: int((g["loads"][c] if c in g["loads"] else g["loads"]["grid_" + c]).shape[-1])
                for c in self.channels}
            f = self._file(self._shard_of(ok[0]))
            if "scene" in f:
                self.scene_text = _text(f["scene"][()])

    # ---- handles ---------------------------------------------------------------------------
    def _file(self, k):
        if os.getpid() != self._pid:
            # Inherited through fork: the parent's handles are not ours to use or close.
            self._files, self._shape_cache, self._pid = {}, OrderedDict(), os.getpid()
        f = self._files.get(k)
        if f is None:
            e = self._shards.get(k)
            if e is None:
                raise KeyError(f"shard {k} is missing from {self.path}")
            f = h5py.File(os.path.join(self.path, e["file"]), "r")
            self._files[k] = f
        return f

    def _shard_of(self, shape_id):
        if not 0 <= shape_id < self.n_shapes:
            raise KeyError(f"shape {shape_id} out of range [0, {self.n_shapes})")
        return shape_id // self.shard_size

    def _group(self, shape_id):
        return self._file(self._shard_of(shape_id))["shapes"][f"{shape_id:06d}"]

    def close(self):
        """Closes every shard handle (they reopen on the next read)."""
        if os.getpid() == self._pid:
            for f in self._files.values():
                try:
                    f.close()
                except Exception:
                    pass
        self._files, self._shape_cache = {}, OrderedDict()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __del__(self):
        try:
            self.close()
        except Exception:
            pass

    def __getstate__(self):
        state = self.__dict__.copy()
        state["_files"], state["_shape_cache"] = {}, OrderedDict()
        return state

    def __setstate__(self, state):
        self.__dict__.update(state)
        self._pid = os.getpid()

    # ---- what is there ---------------------------------------------------------------------
    def shape_ids(self, split=None, include_failed=False):
        """Shape ids of a split ("train", "val", "test") or of the whole dataset (None), sorted.
        Failed shapes are in no split; with split=None they are listed if include_failed."""
        if split is not None:
            if split not in SPLITS:
                raise ValueError(f"unknown split {split!r}: one of {SPLITS}")
            if self.splits is None:
                raise ValueError(f"{self.path}: no splits.json (incomplete dataset)")
            return [int(i) for i in self.splits[split]]
        present = set()
        for e in self._shards.values():
            present.update(range(int(e["first_shape"]), int(e["first_shape"]) + int(e["n_shapes"])))
        failed = set(self.failed_shapes)
        return sorted(i for i in present if include_failed or i not in failed)

    def load_status(self, shape_id):
        """(L,) int8 of a shape: 1 converged, 0 failed (all 0 for a failed shape)."""
        if self._status is None:
            self._status = {}
        s = self._status.get(shape_id)
        if s is None:
            if shape_id in self.failed_shapes:
                s = np.zeros(self.n_loads, np.int8)
            else:
                s = self._group(shape_id)["loads/status"][...]
            self._status[shape_id] = s
        return s

    def keys(self, split=None, include_failed=False):
        """[(shape_id, load_id), ...] in order: converged load cases of the split's shapes, or,
        with include_failed, every load case (failed shapes too when split is None)."""
        out = []
        for sid in self.shape_ids(split, include_failed):
            st = self.load_status(sid)
            out.extend((sid, l) for l in range(self.n_loads) if include_failed or st[l] == 1)
        return out

    def __len__(self):
        return sum(int(self.load_status(i).sum()) for i in self.shape_ids())

    # ---- reading ---------------------------------------------------------------------------
    def shape(self, shape_id):
        """The Shape (cached: the last few shapes read stay in memory)."""
        shape_id = int(shape_id)
        if os.getpid() != self._pid:
            self._file(self._shard_of(shape_id))  # resets inherited state
        sh = self._shape_cache.get(shape_id)
        if sh is None:
            sh = Shape(self, shape_id)
            self._shape_cache[shape_id] = sh
            while len(self._shape_cache) > self._cache_size:
                self._shape_cache.popitem(last=False)
        else:
            self._shape_cache.move_to_end(shape_id)
        return sh

    def shapes(self, split=None, include_failed=False):
        for sid in self.shape_ids(split, include_failed):
            yield self.shape(sid)

    def sample(self, shape_id, load_id, grid=True, point_cloud=True):
        """One load case. Reads one chunk per per-load array (grid=False / point_cloud=False
        skip those arrays). A failed load case comes back with status 0, zero fields and its
        reason; a load case of a failed shape with status 0, reason "shape failed: ..." and no
        arrays (None)."""
        shape_id, load_id = int(shape_id), int(load_id)
        if not 0 <= load_id < self.n_loads:
            raise KeyError(f"load case {load_id} out of range [0, {self.n_loads})")
        sh = self.shape(shape_id)
        kw = dict(shape_id=shape_id, load_id=load_id, dim=self.dim, status=int(sh.status[load_id]),
                  reason=sh.reasons[load_id], nodes=sh.nodes, cells=sh.cells,
                  dirichlet_mask=sh.dirichlet_mask, neumann_mask=sh.neumann_mask,
                  displacement=None, point_cloud={}, grid={}, p_n=None, g=None, params={})
        for k in _LOAD_SCALARS:
            kw[k] = 0 if k in _LOAD_COUNTS else float("nan")
        if not sh.ok:
            kw["target"] = float("nan")
            return Sample(**kw)
        gl = self._group(shape_id)["loads"]
        for k in _LOAD_SCALARS:
            if k in gl:
                v = gl[k][load_id]
                kw[k] = int(v) if np.issubdtype(gl[k].dtype, np.integer) else float(v)
        if "p_n" in gl:
            kw["p_n"], kw["g"] = gl["p_n"][load_id], gl["g"][load_id]
        kw["displacement"] = gl["displacement"][load_id]
        kw["params"] = {k: (v[0] if v.shape == (1,) else v[load_id]) for k, v in sh.params.items()}
        if point_cloud and sh.point_cloud:
            pc = dict(sh.point_cloud)
            for k in self.channels:
                if k in gl:
                    pc[k] = gl[k][load_id]
            kw["point_cloud"] = pc
        if grid and sh.grid:
            gd = dict(sh.grid)
            for k in self.channels + ["displacement"]:
                if f"grid_{k}" in gl:
                    gd[k] = gl[f"grid_{k}"][load_id]
            kw["grid"] = gd
        return Sample(**kw)

    def samples(self, split=None, include_failed=False, grid=True, point_cloud=True):
        """Iterates Samples lazily in (shape, load) order: converged load cases of the split
        (None: all shapes); include_failed adds failed load cases and failed shapes."""
        for sid, lid in self.keys(split, include_failed):
            yield self.sample(sid, lid, grid=grid, point_cloud=point_cloud)

    def __iter__(self):
        return self.samples()

    def field_stats(self, field):
        """(mean, std, rms) arrays (one entry per component) of a stats.json field, computed on
        the train split: sdf, dirichlet_distance, traction, displacement (nodes), grid_sdf,
        grid_dirichlet_distance, grid_traction, grid_displacement (grid), alpha."""
        if self.stats is None:
            raise ValueError(f"{self.path}: no stats.json (incomplete dataset)")
        f = self.stats["fields"][field]
        return (np.asarray(f["mean"], float), np.asarray(f["std"], float), np.asarray(f["rms"], float))

    def __repr__(self):
        t = self.manifest["totals"]
        return (f"Dataset({self.name!r}, {self.dim}D, {self.n_shapes} shapes x {self.n_loads} load cases, "
                f"{t['load_cases_converged']} converged, {t['load_cases_failed']} failed, {self.path})")


def _channels_of(loads):
    """The input channels of a shape's loads group: fields per load case other than the
    displacement (at the nodes, or on the grid only), traction first."""
    names = set()
    for k, v in loads.items():
        base = k[5:] if k.startswith("grid_") else k
        if isinstance(v, h5py.Dataset) and v.ndim >= 3 and base != "displacement":
            names.add(base)
    return sorted(names, key=lambda n: (n != "traction", n))


def open_dataset(path, cache_shapes=4):
    """Opens a dataset directory written by `hypershape generate` (reads the JSON files only;
    shards are opened when first read). `cache_shapes`: how many Shapes stay in memory."""
    return Dataset(path, cache_shapes=cache_shapes)


def _read_json(path):
    with open(path) as f:
        return json.load(f)


# ---------------------------------------------------------------------------------------------
# The paper's metrics (section 4): discrete L2 and H1 norms over the mesh points
#   ||u||_{L2_N}^2 = 1/N_p sum_i |u^i|^2
#   ||u||_{H1_N}^2 = 1/N_p sum_i (|u^i|^2 + sum_k |d_{x_k} u^i|^2)
#   rel_L2(u, u_hat) = ||u - u_hat||_{L2_N} / ||u||_{L2_N}   (u: ground truth), same for H1.
# ---------------------------------------------------------------------------------------------

def norm_l2(u):
    """Discrete L2 norm over the points: sqrt(mean_i |u^i|^2). u: (..., n, c) or (n,); the
    leading axes are a batch."""
    u = np.asarray(u, dtype=float)
    if u.ndim == 1:
        u = u[:, None]
    return np.sqrt(np.mean(np.sum(u * u, axis=-1), axis=-1))


def rel_l2(u, u_hat):
    """Relative L2 error ||u - u_hat||_{L2_N} / ||u||_{L2_N} of a prediction u_hat against the
    ground truth u, both (..., n, d) at the same n mesh points."""
    u, u_hat = np.asarray(u, dtype=float), np.asarray(u_hat, dtype=float)
    if u.shape != u_hat.shape:
        raise ValueError(f"shapes differ: {u.shape} vs {u_hat.shape}")
    return norm_l2(u - u_hat) / norm_l2(u)


# Barycentric coordinates of the nodes of a P1/P2 simplex in VTK order, and the P2 edges.
_P2_EDGES = {2: [(0, 1), (1, 2), (2, 0)], 3: [(0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3)]}


def _basis_gradients_at_nodes(dim, k):
    """C[n, j, a]: d phi_j / d lambda_a at local node n, for the k-node simplex (VTK order).
    Gradients in x follow as sum_a C[n, j, a] grad(lambda_a)."""
    nv = dim + 1
    if k == nv:  # P1: phi_j = lambda_j
        return np.broadcast_to(np.eye(nv), (nv, nv, nv)).copy()
    edges = _P2_EDGES[dim]
    if k != nv + len(edges):
        raise ValueError(f"{k} nodes per cell is neither P1 nor P2 in {dim}D")
    bary = np.zeros((k, nv))
    bary[:nv] = np.eye(nv)
    for e, (a, b) in enumerate(edges):
        bary[nv + e, [a, b]] = 0.5
    C = np.zeros((k, k, nv))
    for n in range(k):
        lam = bary[n]
        for j in range(nv):  # vertex j: lambda_j (2 lambda_j - 1)
            C[n, j, j] = 4 * lam[j] - 1
        for e, (a, b) in enumerate(edges):  # edge (a, b): 4 lambda_a lambda_b
            C[n, nv + e, a] = 4 * lam[b]
            C[n, nv + e, b] = 4 * lam[a]
    return C


def nodal_gradient(u, nodes, cells):
    """Gradient of the finite-element interpolant of nodal values, recovered at the nodes.

    u: (n,) or (n, c) values at the n nodes; nodes: (n, d); cells: (m, k) in VTK order, P1 or
    P2 (k = d + 1 or the P2 count; straight-sided: the geometry is the vertices').
    Returns (n, c, d) (or (n, d) for 1-D u): for each cell the gradient of the P1/P2 interpolant
    evaluated at each of its nodes, averaged over the cells sharing the node, weighted by cell
    volume. Exact wherever u is a polynomial the space contains (linear for P1, quadratic for
    P2). Nodes in no cell get 0."""
    u = np.asarray(u, dtype=float)
    scalar = u.ndim == 1
    if scalar:
        u = u[:, None]
    x = np.asarray(nodes, dtype=float)
    cells = np.asarray(cells, dtype=np.int64)
    d = x.shape[1]
    m, k = cells.shape
    nv = d + 1
    verts = x[cells[:, :nv]]                          # (m, d+1, d)
    J = (verts[:, 1:, :] - verts[:, :1, :])           # (m, d, d): rows x_a - x_0
    det = np.linalg.det(J)
    if np.any(det == 0):
        raise ValueError("degenerate cell (zero volume)")
    # grad(lambda_a), a = 1..d: columns of J^{-1}; grad(lambda_0) = -sum.
    Jinv = np.linalg.inv(J)                           # (m, d, d): Jinv[:, :, a-1] = grad lambda_a
    gl = np.empty((m, nv, d))
    gl[:, 1:, :] = np.transpose(Jinv, (0, 2, 1))
    gl[:, 0, :] = -gl[:, 1:, :].sum(axis=1)
    C = _basis_gradients_at_nodes(d, k)               # (k nodes, k basis, nv)
    uc = u[cells]                                     # (m, k basis, c)
    # grad u at local node n of cell: sum_j u_j (x) sum_a C[n, j, a] grad lambda_a
    G = np.einsum("njv,mvd,mjc->mncd", C, gl, uc)     # (m, k nodes, c, d)
    w = np.abs(det)[:, None] * np.ones((1, k))        # volume weights (constant factor drops)
    n = len(x)
    acc = np.zeros((n, u.shape[1], d))
    wsum = np.zeros(n)
    np.add.at(acc, cells.ravel(), (G * w[:, :, None, None]).reshape(m * k, u.shape[1], d))
    np.add.at(wsum, cells.ravel(), w.ravel())
    acc[wsum > 0] /= wsum[wsum > 0, None, None]
    return acc[:, 0, :] if scalar else acc


def norm_h1(u, nodes, cells, grad=None):
    """Discrete H1 norm sqrt(1/N sum_i (|u^i|^2 + sum_k |d_k u^i|^2)) with the gradients of
    nodal_gradient (or `grad`, (n, c, d), if given). u: (n, c)."""
    u = np.asarray(u, dtype=float)
    if u.ndim == 1:
        u = u[:, None]
    if grad is None:
        grad = nodal_gradient(u, nodes, cells)
    return math.sqrt(float(np.mean(np.sum(u * u, axis=1) + np.sum(grad * grad, axis=(1, 2)))))


def rel_h1(u, u_hat, nodes, cells):
    """Relative H1 error ||u - u_hat||_{H1_N} / ||u||_{H1_N} at the n mesh points (the paper's
    eq. in section 4). u, u_hat: (n, d); nodes (n, d), cells (m, k) of the sample.

    The paper does not say how the derivatives at the mesh points are obtained. Here they are
    the gradient of the P1 (or P2) finite-element interpolant of the nodal values, averaged over
    the cells around each node with cell-volume weights (nodal_gradient), the usual recovered
    nodal gradient of the FE solution; exact for linear (P1) / quadratic (P2) fields. Both u and
    u_hat are differentiated this way (the gradient is linear in the field)."""
    u, u_hat = np.asarray(u, dtype=float), np.asarray(u_hat, dtype=float)
    if u.shape != u_hat.shape:
        raise ValueError(f"shapes differ: {u.shape} vs {u_hat.shape}")
    return norm_h1(u - u_hat, nodes, cells) / norm_h1(u, nodes, cells)


# ---------------------------------------------------------------------------------------------
# The grid: x_i = -1 + 2 i / (N - 1) on every axis, arrays in numpy 'ij' order (x index first)
# ---------------------------------------------------------------------------------------------

def grid_axis(n):
    """The N grid coordinates of one axis, exactly as the C++ writes them."""
    i = np.arange(n, dtype=float)
    return (2 * i - (n - 1)) / (n - 1)


def grid_points(dim, n):
    """(N,)*dim + (dim,) coordinates of the grid, 'ij' order: p[i, j] = (x_i, y_j)."""
    ax = grid_axis(n)
    return np.stack(np.meshgrid(*([ax] * dim), indexing="ij"), axis=-1)


def grid_to_mesh(values, points):
    """Bilinear (2D) / trilinear (3D) interpolation of grid values at arbitrary points, the way
    the paper evaluates grid predictions at the mesh points.

    values: (N,)*d + trailing channel axes (e.g. (N, N, 2) for a 2D vector field, (N, N, N) for
    a 3D scalar); d = points.shape[1]. points: (n, d) in [-1, 1]^d (clamped to it).
    Returns (n,) + trailing axes, float64. Reproduces any function linear in each coordinate
    exactly (in particular every affine field)."""
    v = np.asarray(values)
    p = np.asarray(points, dtype=float)
    d = p.shape[1]
    N = v.shape[0]
    if v.shape[:d] != (N,) * d:
        raise ValueError(f"values {v.shape}: the first {d} axes must be the grid ({N},)*{d}")
    s = (np.clip(p, -1.0, 1.0) + 1.0) * 0.5 * (N - 1)
    i0 = np.clip(np.floor(s).astype(np.int64), 0, N - 2)
    t = s - i0                                      # in [0, 1]
    out = 0.0
    for corner in range(1 << d):
        idx, w = [], np.ones(len(p))
        for a in range(d):
            bit = (corner >> a) & 1
            idx.append(i0[:, a] + bit)
            w = w * (t[:, a] if bit else 1.0 - t[:, a])
        vals = v[tuple(idx)].astype(float)
        out = out + vals * w.reshape((-1,) + (1,) * (vals.ndim - 1))
    return out


# ---------------------------------------------------------------------------------------------
# Command line: summary, check
# ---------------------------------------------------------------------------------------------

def _walk(group, prefix=""):
    for k, v in group.items():
        path = f"{prefix}/{k}" if prefix else k
        if isinstance(v, h5py.Group):
            yield from _walk(v, path)
        else:
            yield path, v


def _nonfinite_attributes(h):
    """Paths of numeric attributes (file, groups, datasets) holding NaN or Inf."""
    bad = []

    def look(name, obj):
        for k, v in obj.attrs.items():
            a = np.asarray(v)
            if a.dtype.kind in "fc" and not np.isfinite(a).all():
                bad.append(f"/{name}@{k}" if name else f"/@{k}")
    look("", h)
    h.visititems(look)
    return bad


def summary(path, out=sys.stdout):
    """Prints counts, splits, statistics and the shape/dtype/units of every array of one shape."""
    ds = open_dataset(path)
    m, t = ds.manifest, ds.manifest["totals"]
    w = lambda s="": print(s, file=out)  # noqa: E731
    w(f"dataset {ds.name!r} in {ds.path}")
    w(f"  {ds.dim}D, {ds.n_shapes} shapes x {ds.n_loads} load cases, {len(m['shards'])} shards of "
      f"{ds.shard_size} shapes, grid {ds.grid_size if ds.grid_size else '-'}"
      f"{'' if m['complete'] else ', INCOMPLETE: missing shards ' + str(m['missing_shards'])}")
    w(f"  shapes: {t['shapes_ok']} ok, {t['shapes_failed']} failed {ds.failed_shapes or ''}")
    w(f"  load cases: {t['load_cases_converged']} converged, {t['load_cases_failed']} failed")
    if ds.splits:
        w("  splits (shapes / converged load cases):")
        for s in SPLITS:
            ids = ds.shape_ids(s)
            w(f"    {s:<6}{len(ids):6d} / {len(ds.keys(s)):<8d} fraction {ds.splits['fractions'][s]}")
    if ds.stats:
        w(f"  statistics over the train split ({ds.stats['n_shapes']} shapes), per component:")
        w(f"    {'field':<24}{'count':>10}  {'mean':<28}{'std':<28}{'rms':<28}")
        fmt = lambda a: "[" + ", ".join(f"{x:.4g}" for x in a) + "]"  # noqa: E731
        for k, f in sorted(ds.stats["fields"].items()):
            w(f"    {k:<24}{int(f['count'][0]):>10}  {fmt(f['mean']):<28}{fmt(f['std']):<28}{fmt(f['rms']):<28}")
    est = error_estimates(ds)
    if est is not None:
        print_error_estimates(est, out)
    ok = ds.shape_ids()
    if ok:
        sid = ok[0]
        g = ds._group(sid)
        w(f"  arrays of shape {sid} (group /shapes/{sid:06d} of {ds._shards[ds._shard_of(sid)]['file']}):")
        for p, v in _walk(g):
            units = _text(v.attrs["units"]) if "units" in v.attrs else ""
            meaning = _text(v.attrs["meaning"]) if "meaning" in v.attrs else ""
            w(f"    {p:<31} {str(v.shape):<20}{str(v.dtype):<9}{units:<20}{meaning}")
    ds.close()
    return 0


def shape_error_estimates(ds, shape_id):
    """(L, 3) float64: error_estimate_rel_l2, _max_u, _alpha of every load case of a shape (NaN
    when the dataset stores none)."""
    gl = ds._group(shape_id)["loads"]
    if ERROR_ESTIMATES[0] not in gl:
        return np.full((ds.n_loads, 3), np.nan)
    return np.stack([gl[k][...] for k in ERROR_ESTIMATES], axis=1).astype(np.float64)


# A label that took more than this many times the dataset's median Newton iterations is counted
# as possibly near a limit point of the load, where the estimate can undershoot (docs/ACCURACY.md,
# "Random2D at P2": 7x on a label of 76 iterations against a median of 17). A warning count, not a
# classification: most such labels are well estimated.
NEAR_LIMIT_ITERATIONS = 3.0


def error_estimates(ds, worst=5):
    """The labels' own error estimates over a dataset's converged load cases: per estimate its
    distribution (quantiles of the magnitude), the `worst` load cases by the relative L2 estimate
    (with their Newton iterations), and how many estimated labels took more than
    NEAR_LIMIT_ITERATIONS x the median Newton iterations. None when the dataset stores no estimates."""
    rows, its, levels = [], [], []  # (shape, load, rel_l2, max_u, alpha); Newton iterations; ladder levels
    for sid in ds.shape_ids():
        gl = ds._group(sid)["loads"]
        if ERROR_ESTIMATES[0] not in gl:
            return None
        st = gl["status"][...]
        cols = [gl[k][...] for k in ERROR_ESTIMATES]
        n_it = gl["newton_iterations"][...]
        rows += [(sid, k, *(float(c[k]) for c in cols)) for k in range(len(st)) if st[k]]
        its += [int(n_it[k]) for k in range(len(st)) if st[k]]
        if "accuracy_level" in gl:
            levels += [int(v) for v, k in zip(gl["accuracy_level"][...], st) if k]
    if not rows:
        return None
    a = np.array([r[2:] for r in rows])
    its = np.array(its)
    missing = int((a[:, 0] < 0).sum())  # -1: no estimate could be formed
    inverted = int((a[:, 0] == -2).sum())  # -2: nor can be, the label inverts inside a cell
    rows = [r for r, k in zip(rows, a[:, 0] >= 0) if k]
    its = its[a[:, 0] >= 0]
    a = a[a[:, 0] >= 0]
    if not rows:
        return {"load_cases": 0, "without_estimate": missing, "inverted_in_a_cell": inverted,
                "distribution_of_magnitude": {}, "worst_by_rel_l2": [], "many_newton_iterations": 0}
    q = (50, 90, 99, 100)
    dist = {k: {f"p{p}": float(np.percentile(np.abs(a[:, i]), p)) for p in q} for i, k in enumerate(ERROR_ESTIMATES)}
    order = np.argsort(-a[:, 0])[:worst]
    return {"load_cases": len(rows), "without_estimate": missing, "inverted_in_a_cell": inverted,
            "labels_per_accuracy_level": {k: levels.count(k) for k in sorted(set(levels))},
            "distribution_of_magnitude": dist,
            "worst_by_rel_l2": [{"shape": rows[i][0], "load": rows[i][1], "rel_l2": rows[i][2],
                                 "max_u": rows[i][3], "alpha": rows[i][4],
                                 "newton_iterations": int(its[i])} for i in order],
            "many_newton_iterations": int((its > NEAR_LIMIT_ITERATIONS * np.median(its)).sum())}


def print_error_estimates(e, out=sys.stdout):
    w = lambda s: print(s, file=out)  # noqa: E731
    w(f"  label error estimates over {e['load_cases']} converged load cases (|value| quantiles; "
      f"{e['without_estimate']} without an estimate"
      + (f", {e['inverted_in_a_cell']} of them because the label inverts inside a cell" if e.get("inverted_in_a_cell") else "")
      + "):")
    for k, d in e["distribution_of_magnitude"].items():
        w(f"    {k:<24}" + "  ".join(f"{p} {v:.3g}" for p, v in d.items()))
    w("    worst load cases by rel_l2: " + ", ".join(
        f"shape {r['shape']} load {r['load']} ({r['rel_l2']:.3g}, {r['newton_iterations']} Newton its)"
        for r in e["worst_by_rel_l2"]))
    if e.get("labels_per_accuracy_level"):
        w("    labels per accuracy level (asked for by accuracy): "
          + ", ".join(f"{k}: {n}" for k, n in e["labels_per_accuracy_level"].items()))
    w(f"    {e['many_newton_iterations']} estimated labels took more than {NEAR_LIMIT_ITERATIONS:g}x the median Newton "
      "iterations: near a limit point of the load an estimate can undershoot (docs/ACCURACY.md)")


def check_dataset(path, out=sys.stdout):
    """Verifies a dataset: every shard listed in manifest.json exists with the listed size and
    CRC-32 and opens as a complete shard of this dataset, and every numeric array and attribute
    in every shard is finite. Returns the list of problems (empty if sound)."""
    problems = []
    say = lambda s: print(s, file=out)  # noqa: E731
    try:
        m = _read_json(os.path.join(path, "manifest.json"))
    except (OSError, ValueError) as e:
        return [f"manifest.json: {e}"]
    if not m.get("complete", False):
        problems.append(f"manifest: dataset incomplete, missing shards {m.get('missing_shards')}")
    listed = {os.path.basename(e["file"]) for e in m["shards"]}
    sdir = os.path.join(path, "shards")
    for extra in sorted(set(os.listdir(sdir)) - listed) if os.path.isdir(sdir) else []:
        say(f"  note: shards/{extra} is not listed in manifest.json (not checked)")
    for e in m["shards"]:
        f = os.path.join(path, e["file"])
        if not os.path.exists(f):
            problems.append(f"{e['file']}: missing")
            continue
        crc = 0
        with open(f, "rb") as fh:
            for block in iter(lambda: fh.read(1 << 20), b""):
                crc = zlib.crc32(block, crc)
        crc_hex = f"{crc & 0xFFFFFFFF:08x}"
        size = os.path.getsize(f)
        if crc_hex != e["crc32"] or size != int(e["bytes"]):
            problems.append(f"{e['file']}: CRC-32 {crc_hex} / {size} bytes, manifest says {e['crc32']} / {e['bytes']}")
        bad, n_arrays = [], 0
        try:
            with h5py.File(f, "r") as h:
                if _text(h.attrs.get("config_hash", b"")) != m["config_hash"] or h.attrs.get("complete") != 1:
                    bad.append("not a complete shard of this dataset (config_hash / complete)")
                bad.extend(f"{a}: NaN/Inf attribute" for a in _nonfinite_attributes(h))
                for p, v in _walk(h):
                    if v.dtype.kind in "fc":
                        n_arrays += 1
                        a = v[()]
                        if not np.isfinite(a).all():
                            bad.append(f"/{p}: {int(np.size(a) - np.isfinite(a).sum())} NaN/Inf values")
                    elif v.dtype.kind in "iu":
                        n_arrays += 1
                        v[()]  # reads (and so checks) the compressed chunks
        except Exception as ex:  # a damaged file: HDF5 or zlib errors
            bad.append(f"unreadable: {type(ex).__name__}: {ex}")
        problems.extend(f"{e['file']}: {b}" for b in bad)
        if not bad:
            say(f"  {e['file']}: crc32 {crc_hex}, {n_arrays} numeric arrays finite")
    return problems


OUTCOMES = ("path", "branch switch from an unstable state", "branch switch after a stall",
            "arc-length rescue", "retry from rest", "from the P1 solution", "other", "failed",
            "failed at a verified fold",
            "shape failed")


def load_case_outcome(status, reason):
    """How a load case's solve ended, from its stored status and reason (docs/FORMAT.md): on the
    path itself, after a branch switch from an unstable state on target (a bifurcation or a
    fold) or from a stalled path, by the arc-length rescue, by the retry from rest without the
    first-increment hint, from the P1 solution on the same mesh (a P2 dataset's last rescue:
    SolverOptions::p1_start), otherwise converged, or failed: at a verified fold (the path from rest
    passed a limit point of the load, so its state on target is unstable, and no branch switch
    found a stable one: docs/STABILITY.md) or otherwise."""
    if not status:
        return "failed at a verified fold" if reason.startswith("fold:") else "failed"
    if reason == "target reached":
        return "path"
    if reason.startswith("target reached after a branch switch ("):
        unstable = reason.startswith(("target reached after a branch switch (loss of stability",
                                      "target reached after a branch switch (fold"))
        return "branch switch from an unstable state" if unstable else "branch switch after a stall"
    if reason.startswith("target reached by arc-length continuation"):
        return "arc-length rescue"
    if reason.startswith("target reached from rest without the first-increment hint"):
        return "retry from rest"
    if reason.startswith("target reached from the P1 solution on the same mesh"):
        return "from the P1 solution"
    return "other"


def _reason_kind(reason):
    """A failure reason with its numbers replaced by '#': failures grouped by kind."""
    return re.sub(r"[-+]?\d+(\.\d+)?(e[-+]?\d+)?", "#", reason)


def solver_report(path):
    """Solver outcomes of a dataset: load cases converged, failures grouped by reason, Newton
    iterations per load case, the cost of recovery (iterations spent in failed increments) and
    the load cases and Newton iterations by outcome (load_case_outcome; "shape failed": the load
    cases of a shape that was never solved, without iterations). Returns a dict (JSON-ready)."""
    ds = open_dataset(path)
    its, rec, inc, fails, status = [], [], [], {}, []
    by = {o: {"load_cases": 0, "newton_iterations": 0} for o in OUTCOMES}
    for sid in ds.shape_ids(include_failed=True):
        sh = ds.shape(sid)
        if not sh.ok:
            for r in sh.reasons:
                status.append(0)
                by["shape failed"]["load_cases"] += 1
                key = _reason_kind(r)
                fails[key] = fails.get(key, 0) + 1
            continue
        g = ds._group(sid)["loads"]
        shape_its = [int(x) for x in g["newton_iterations"][...]]
        its += shape_its
        rec += list(g["recovery_iterations"][...]) if "recovery_iterations" in g else [0] * len(sh.reasons)
        inc += list(g["solves"][...])
        for k, r in enumerate(sh.reasons):
            status.append(int(sh.status[k]))
            o = by[load_case_outcome(sh.status[k], r)]
            o["load_cases"] += 1
            o["newton_iterations"] += shape_its[k]
            if not sh.status[k]:
                key = _reason_kind(r)
                fails[key] = fails.get(key, 0) + 1
    ds.close()
    its, rec, status = np.array(its, float), np.array(rec, float), np.array(status)
    n = len(status)
    pct = lambda q: float(np.percentile(its, q)) if len(its) else 0.0  # noqa: E731
    folds = by["failed at a verified fold"]["load_cases"]
    return {"dataset": path, "load_cases": n, "converged": int(status.sum()),
            "converged_percent": 100.0 * status.sum() / max(n, 1),
            "verified_folds": folds,  # and the share converged of the other load cases:
            "converged_percent_without_folds": 100.0 * status.sum() / max(n - folds, 1),
            "failures_by_reason": dict(sorted(fails.items(), key=lambda kv: -kv[1])),
            "newton_iterations": {"total": int(its.sum()), "mean": float(its.mean()) if len(its) else 0.0,
                                  "median": pct(50), "p90": pct(90), "p99": pct(99),
                                  "max": float(its.max()) if len(its) else 0.0},
            "increments_per_load_case_mean": float(np.mean(inc)) if inc else 0.0,
            "recovery_iterations": {"total": int(rec.sum()),
                                    "share_of_newton_iterations": float(rec.sum() / max(its.sum(), 1)),
                                    "load_cases_with_recovery": int((rec > 0).sum())},
            "by_outcome": {o: v for o, v in by.items() if v["load_cases"]}}


def print_solver_report(r, out=sys.stdout):
    w = lambda s: print(s, file=out)  # noqa: E731
    it, rc = r["newton_iterations"], r["recovery_iterations"]
    folds = r.get("verified_folds", 0)
    w(f"{r['dataset']}: {r['converged']}/{r['load_cases']} load cases converged ({r['converged_percent']:.2f}%)"
      + (f"; {folds} failed at a verified fold (no stable state on target on the path or a switched branch), so "
         f"{r['converged_percent_without_folds']:.2f}% of the others" if folds else ""))
    w(f"  Newton iterations per load case: mean {it['mean']:.1f}, median {it['median']:.0f}, "
      f"p90 {it['p90']:.0f}, p99 {it['p99']:.0f}, max {it['max']:.0f}; "
      f"{r['increments_per_load_case_mean']:.1f} increments per load case")
    w(f"  recovery (iterations in failed increments): {rc['total']} = {100 * rc['share_of_newton_iterations']:.1f}% "
      f"of all, in {rc['load_cases_with_recovery']} load cases")
    by = r.get("by_outcome", {})
    if by:
        w("  by outcome (load cases, Newton iterations each): " + "; ".join(
            f"{o} {v['load_cases']}" + ("" if o == "shape failed" else f" ({v['newton_iterations'] / v['load_cases']:.1f})")
            for o, v in by.items()))
    for reason, k in r["failures_by_reason"].items():
        w(f"  failed {k:>5} x  {reason}")


def _add_plot_parser(sub):
    pp = sub.add_parser("plot", help="pictures of solutions: deformed shape coloured by |u|, Dirichlet "
                                     "patch, load (matplotlib; scripts/hypershape_plot.py)")
    pp.add_argument("dir")
    pp.add_argument("--shape", type=int, nargs="+", help="shape ids (default: the first solved shape)")
    pp.add_argument("--load", type=int, nargs="+", default=[0], help="load case ids (default 0)")
    pp.add_argument("-o", "--output", help="PNG file (default: shape-I-load-J.png)")
    pp.add_argument("--cols", type=int, help="panels per row (default: up to 4)")
    pp.add_argument("--scale", type=float, default=1.0, help="displacement magnification (default 1)")
    pp.add_argument("--gallery", type=int, metavar="N",
                    help="instead of --shape/--load: the first N converged load cases, load 0 of each "
                         "shape first, then load 1, ...")


def plot_command(a):
    """`plot`: one panel per (shape, load case); bad ids stop with the option named, exit 2."""
    try:
        ds = open_dataset(a.dir)
    except (OSError, ValueError, KeyError) as e:
        print(f"plot: cannot open dataset {a.dir}: {e}", file=sys.stderr)
        return 2
    solved = ds.shape_ids()
    shapes = a.shape if a.shape is not None else solved[:1]
    bad = [i for i in shapes if i not in solved]
    if bad or not shapes:
        print(f"plot: --shape {bad or shapes}: not a solved shape of {a.dir} (solved: "
              f"{solved[:10]}{' ...' if len(solved) > 10 else ''})", file=sys.stderr)
        return 2
    bad = [j for j in a.load if not 0 <= j < ds.n_loads]
    if bad:
        print(f"plot: --load {bad}: out of range [0, {ds.n_loads})", file=sys.stderr)
        return 2
    pairs = [(i, j) for i in shapes for j in a.load]
    if a.gallery:
        pairs = [(i, j) for j in range(ds.n_loads) for i in solved if ds.load_status(i)[j] == 1][: a.gallery]
    if not pairs:
        print(f"plot: --gallery: no converged load case in {a.dir}", file=sys.stderr)
        return 2
    out = a.output or f"shape-{pairs[0][0]}-load-{pairs[0][1]}.png"
    import hypershape_plot
    hypershape_plot.plot(ds, pairs, out, a.cols, a.scale)
    print(f"plot: {len(pairs)} panel(s) -> {out}")
    return 0


def _main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="command", required=True)
    sub.add_parser("summary", help="counts, splits, statistics, array shapes").add_argument("dir")
    sub.add_parser("check", help="CRC-32 against manifest.json, no NaN/Inf; exit 1 otherwise").add_argument("dir")
    sp = sub.add_parser("solver", help="convergence rate, failure reasons, Newton and recovery cost")
    sp.add_argument("dir")
    sp.add_argument("--json", help="also write the figures here")
    _add_plot_parser(sub)
    a = ap.parse_args(argv)
    if a.command == "plot":
        return plot_command(a)
    if a.command == "solver":
        r = solver_report(a.dir)
        print_solver_report(r)
        if a.json:
            with open(a.json, "w") as f:
                json.dump(r, f, indent=1)
        return 0
    if a.command == "summary":
        try:
            return summary(a.dir)
        except (OSError, ValueError, KeyError) as e:
            print(f"summary: {e}", file=sys.stderr)
            return 1
    problems = check_dataset(a.dir)
    for p in problems:
        print(f"FAIL {p}")
    print(f"check {a.dir}: " + ("ok" if not problems else f"{len(problems)} problems"))
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(_main())
