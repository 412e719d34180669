#!/usr/bin/python3
"""PyTorch Datasets over a hypershape dataset directory (Debian's python3-torch), for the two
forms of the seed paper (section 3.3): the grid form (FNO, CNO, U-Net) and the point-cloud form
(GINO, Transolver). Reading goes through scripts/hypershape_data.py (numpy + h5py).

    import sys; sys.path.insert(0, "scripts")
    import torch, hypershape_torch as ht

    train = ht.GridDataset("/tmp/pyds", "train", normalize="channelwise")
    loader = torch.utils.data.DataLoader(train, batch_size=8, shuffle=True, num_workers=2)
    for batch in loader:
        x, y = batch["x"], batch["y"]          # (B, 2 + d, N, N[, N]), (B, d, N, N[, N])

    pc = ht.PointCloudDataset("/tmp/pyds", "test")
    loader = torch.utils.data.DataLoader(pc, batch_size=4, collate_fn=ht.collate_padded)
    for batch in loader:                       # padded to the largest point count in the batch
        pos, x, y, mask = batch["pos"], batch["x"], batch["y"], batch["mask"]

Each item is one converged load case (shape_id, load_id) of a shape of the split; failed load
cases and failed shapes are never served. Items are dicts of tensors (d: dimension, N: grid
points per axis, n: mesh nodes of the shape, m: cells, k: nodes per cell):

  GridDataset
    "x"        (c, N, ..., N) float32  channels (Dataset.x_channels): sdf, dirichlet_distance,
                                       then d components of each input channel the dataset's
                                       effects bring (reader.channels: traction, body_force, ...;
                                       c = 2 + d for the paper's presets: traction only)
    "y"        (d, N, ..., N)     float32  displacement_1..d (closest-boundary-point extension
                                           outside the body)
    "inside"   (N, ..., N)        bool     grid point in the body
    "shape_id", "load_id"         int64    (scalars)
    with_mesh=True adds the mesh, to evaluate on the mesh points as the paper does:
    "nodes" (n, d) float64, "u_mesh" (n, d) float64, "cells" (m, k) int64, "n_points" int64
  PointCloudDataset
    "pos"      (n, d)     float32  node coordinates (the point cloud), not normalised
    "x"        (n, c) float32  sdf, dirichlet_distance, then each input channel at the nodes
                               (x_channels; traction zero off the Neumann boundary)
    "y"        (n, d)     float32  displacement at the nodes
    "n_points", "shape_id", "load_id"  int64
    with_mesh=True adds "cells" (m, k) int64 (for rel_h1).

Both carry "error_estimate" (3,) float64: the label's own estimated error (relative L2 of u;
relative, signed, error of max|u| and of alpha; NaN without estimates, -1 where none could be
formed; docs/ACCURACY.md).
max_error=E keeps only the load cases whose relative L2 estimate is <= E; the dataset's
error_estimates attribute ((len, 3) numpy, item order) lets a user weight samples, e.g.
torch.utils.data.WeightedRandomSampler(1 / (1 + ds.error_estimates[:, 0] / 0.01), len(ds)).

Grid items have one size and batch with the default collate. Point clouds differ in n:
collate_padded pads them and adds "mask" (B, n_max) bool; "cells" stay a list.

Normalisation (normalize=...), from stats.json (computed over the train split only):
  None           raw values (lengths and forces as stored)
  "channelwise"  every input and output channel: (v - mean) / std (the paper's "channelwise"
                 normalisation for FNO, CNO, GINO, Transolver)
  "rms"          traction and displacement divided by their RMS over the train split (one number
                 per field, all components: |v|^2 averaged, so rotations keep their meaning);
                 sdf and dirichlet distance unchanged (the paper's U-Net, appendix)
The dataset's x_mean, x_std, y_mean, y_std (tensors of one value per channel) hold what was
applied: normalised = (raw - mean) / std; denormalize(y) undoes it on predictions.

Workers: each Dataset holds a hypershape_data.Dataset whose shard handles are opened lazily by
the process that reads (a forked worker drops the handles it inherited and opens its own), so
DataLoader(num_workers > 0) is safe. Handles are closed at the end of __init__.
"""
import os
import sys

import numpy as np

try:
    import torch
except ImportError as ex:  # scripts/run.sh installs only what a build and the readers need
    raise ImportError("hypershape_torch needs PyTorch: apt-get install python3-torch "
                      "(or scripts/setup.sh without arguments, as scripts/test.sh runs it)") from ex

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import hypershape_data as hd  # noqa: E402

__all__ = ["GridDataset", "PointCloudDataset", "collate_padded", "rel_l2_loss",
           "rel_h1_grid_loss", "grid_to_mesh_torch"]

NORMALIZATIONS = (None, "channelwise", "rms")


def _field_norm(reader, field, mode, n_comp):
    """(mean, std) per component of a stats.json field for a normalisation mode."""
    if mode is None:
        return np.zeros(n_comp), np.ones(n_comp)
    mean, std, rms = reader.field_stats(field)
    if mode == "channelwise":
        return mean, np.where(std > 0, std, 1.0)
    # rms: one number per vector field, none for the distances
    if field.endswith("sdf") or field.endswith("dirichlet_distance"):
        return np.zeros(n_comp), np.ones(n_comp)
    count = np.asarray(reader.stats["fields"][field]["count"], float)
    r = float(np.sqrt(np.sum(count * rms ** 2) / np.sum(count))) if count.sum() > 0 else 1.0
    return np.zeros(n_comp), np.full(n_comp, r if r > 0 else 1.0)


class _Base(torch.utils.data.Dataset):
    _fields = None  # (sdf, dirichlet distance, channel prefix, displacement) names in stats.json

    def __init__(self, path, split="train", normalize=None, dtype=torch.float32, with_mesh=False, max_error=None):
        if normalize not in NORMALIZATIONS:
            raise ValueError(f"normalize must be one of {NORMALIZATIONS}, got {normalize!r}")
        self.reader = hd.open_dataset(path)
        self.split, self.normalize, self.dtype, self.with_mesh = split, normalize, dtype, with_mesh
        self.dim = d = self.reader.dim
        self.index = self.reader.keys(split)  # (shape_id, load_id), converged only
        per_shape = {sid: hd.shape_error_estimates(self.reader, sid) for sid in sorted({k[0] for k in self.index})}
        est = np.array([per_shape[sid][lid] for sid, lid in self.index]).reshape(-1, 3)
        if max_error is not None:
            keep = (est[:, 0] >= 0) & (est[:, 0] <= max_error)  # -1, -2 / NaN (no estimate): dropped
            self.index = [k for k, ok in zip(self.index, keep) if ok]
            est = est[keep]
        self.error_estimates = est
        sdf, dd, prefix, u = self._fields
        # Inputs: sdf, dirichlet distance, then every channel the dataset's effects bring
        # (traction, body force, ...: Dataset.channels), d components each (pressure and a
        # modulus field: one, named without a suffix).
        self.channels = list(self.reader.channels)
        nc = {c: self.reader.channel_components.get(c, d) for c in self.channels}
        self.x_channels = ["sdf", "dirichlet_distance"] + [
            (f"{c}_{k}" if nc[c] > 1 else c) for c in self.channels for k in "xyz"[:nc[c]]]
        fields = [(sdf, 1), (dd, 1)] + [(prefix + c, nc[c]) for c in self.channels]
        xm, xs = zip(*(_field_norm(self.reader, f, normalize, c) for f, c in fields))
        ym, ys = _field_norm(self.reader, u, normalize, d)
        self.x_mean = torch.tensor(np.concatenate(xm), dtype=dtype)
        self.x_std = torch.tensor(np.concatenate(xs), dtype=dtype)
        self.y_mean = torch.tensor(ym, dtype=dtype)
        self.y_std = torch.tensor(ys, dtype=dtype)
        self.reader.close()  # nothing open when the DataLoader forks its workers

    def __len__(self):
        return len(self.index)

    def keys(self):
        """(shape_id, load_id) of every item, in order."""
        return list(self.index)


class GridDataset(_Base):
    """The grid form of a split: see the module docstring for the item layout."""

    _fields = ("grid_sdf", "grid_dirichlet_distance", "grid_", "grid_displacement")

    def __init__(self, path, split="train", normalize=None, dtype=torch.float32, with_mesh=False, max_error=None):
        super().__init__(path, split, normalize, dtype, with_mesh, max_error)
        if self.reader.grid_size is None:
            raise ValueError(f"{path}: no grid representation stored (representations.grid: false)")
        self.grid_size = self.reader.grid_size
        shape = (-1,) + (1,) * self.dim
        self._xm, self._xs = self.x_mean.view(shape), self.x_std.view(shape)
        self._ym, self._ys = self.y_mean.view(shape), self.y_std.view(shape)

    def __getitem__(self, i):
        sid, lid = self.index[i]
        s = self.reader.sample(sid, lid, grid=True, point_cloud=False)
        g = s.grid
        d = self.dim
        cl = lambda a: np.moveaxis(a, -1, 0)  # noqa: E731  (N.., c) -> (c, N..)
        x = np.concatenate([g["sdf"][None], g["dirichlet_distance"][None]] + [cl(g[c]) for c in self.channels], axis=0)
        x = (torch.as_tensor(x, dtype=self.dtype) - self._xm) / self._xs
        y = (torch.as_tensor(cl(g["displacement"]), dtype=self.dtype) - self._ym) / self._ys
        item = {"x": x, "y": y, "inside": torch.as_tensor(g["inside"]),
                "shape_id": torch.tensor(sid), "load_id": torch.tensor(lid),
                "error_estimate": torch.as_tensor(self.error_estimates[i])}
        if self.with_mesh:
            item.update(nodes=torch.as_tensor(s.nodes), u_mesh=torch.as_tensor(s.displacement),
                        cells=torch.as_tensor(s.cells), n_points=torch.tensor(len(s.nodes)))
        assert x.shape == (len(self.x_channels),) + (self.grid_size,) * d
        return item

    def denormalize(self, y):
        """Undoes the output normalisation of y: (d, N..) or (B, d, N..)."""
        return y * self._ys.to(y) + self._ym.to(y)


class PointCloudDataset(_Base):
    """The point-cloud form of a split: see the module docstring for the item layout."""

    _fields = ("sdf", "dirichlet_distance", "", "displacement")

    def __init__(self, path, split="train", normalize=None, dtype=torch.float32, with_mesh=False, max_error=None):
        super().__init__(path, split, normalize, dtype, with_mesh, max_error)
        s = None
        if self.index:
            s = self.reader.shape(self.index[0][0])
            self.reader.close()
        if s is not None and "sdf" not in s.point_cloud:
            raise ValueError(f"{path}: no point-cloud representation stored (representations.point_cloud: false)")

    def __getitem__(self, i):
        sid, lid = self.index[i]
        s = self.reader.sample(sid, lid, grid=False, point_cloud=True)
        pc = s.point_cloud
        x = np.concatenate([pc["sdf"][:, None], pc["dirichlet_distance"][:, None]] + [pc[c] for c in self.channels], axis=1)
        x = (torch.as_tensor(x, dtype=self.dtype) - self.x_mean) / self.x_std
        y = (torch.as_tensor(s.displacement, dtype=self.dtype) - self.y_mean) / self.y_std
        item = {"pos": torch.as_tensor(s.nodes, dtype=self.dtype), "x": x, "y": y,
                "n_points": torch.tensor(len(s.nodes)), "shape_id": torch.tensor(sid),
                "load_id": torch.tensor(lid), "error_estimate": torch.as_tensor(self.error_estimates[i])}
        if self.with_mesh:
            item["cells"] = torch.as_tensor(s.cells)
        return item

    def denormalize(self, y):
        """Undoes the output normalisation of y: (n, d) or (B, n, d)."""
        return y * self.y_std.to(y) + self.y_mean.to(y)


def collate_padded(batch):
    """Collates dict items whose tensors may differ in their first dimension (point clouds):
    equal shapes are stacked; others are zero-padded along dim 0 to the largest and stacked;
    "cells" stay a list of tensors. If items carry "n_points", adds "mask" (B, n_max) bool,
    True at real points."""
    out = {}
    for key in batch[0]:
        vals = [b[key] for b in batch]
        if not torch.is_tensor(vals[0]) or key == "cells":
            out[key] = vals
        elif all(v.shape == vals[0].shape for v in vals):
            out[key] = torch.stack(vals)
        else:
            n = max(v.shape[0] for v in vals)
            pad = vals[0].new_zeros((len(vals), n) + tuple(vals[0].shape[1:]))
            for b, v in enumerate(vals):
                pad[b, : v.shape[0]] = v
            out[key] = pad
    if "n_points" in out:
        n_max = max([v.shape[1] for k, v in out.items() if k in ("pos", "x", "y", "nodes", "u_mesh")] or [0])
        out["mask"] = torch.arange(n_max)[None, :] < out["n_points"][:, None]
    return out


# ---------------------------------------------------------------------------------------------
# Losses on batches (differentiable): the paper's relative errors
# ---------------------------------------------------------------------------------------------

def rel_l2_loss(pred, true, mask=None, reduction="mean"):
    """Relative L2 error per sample, ||pred - true|| / ||true|| over all points and components
    (the mean over points cancels in the ratio), averaged over the batch.
    Point clouds: (B, n, d) with optional mask (B, n) (padding excluded). Grids: (B, d, N..)
    with optional mask (B, N..) (e.g. batch["inside"]: only points in the body)."""
    diff, ref = (pred - true) ** 2, true ** 2
    if mask is not None:
        m = mask.to(diff.dtype)
        m = m.unsqueeze(-1) if m.shape == diff.shape[:-1] else m.unsqueeze(1)
        diff, ref = diff * m, ref * m
    axes = tuple(range(1, diff.dim()))
    r = torch.sqrt(diff.sum(axes) / ref.sum(axes))
    return r.mean() if reduction == "mean" else r


def rel_h1_grid_loss(pred, true, reduction="mean"):
    """Relative H1 error on the grid, as the paper trains its grid models ("spatial
    derivatives approximated by finite differences"): ||e||_{H1_N} / ||u||_{H1_N} with
    e = pred - true over all grid points, derivatives by second-order central differences
    (one-sided at the box faces) with spacing 2 / (N - 1). pred, true: (B, c, N, ..., N)."""
    d = pred.dim() - 2
    h = 2.0 / (pred.shape[-1] - 1)

    def sq_h1(v):
        s = (v ** 2).flatten(1).sum(1)
        for g in torch.gradient(v, spacing=h, dim=tuple(range(2, 2 + d))):
            s = s + (g ** 2).flatten(1).sum(1)
        return s

    r = torch.sqrt(sq_h1(pred - true) / sq_h1(true))
    return r.mean() if reduction == "mean" else r


def grid_to_mesh_torch(values, points):
    """Differentiable bi/trilinear interpolation of grid fields at points (torch grid_sample,
    align_corners=True: grid node i sits at -1 + 2 i / (N - 1), as stored).
    values: (B, c, N, ..., N) in 'ij' order (x index first); points: (B, n, d) in [-1, 1]^d
    (outside: the border value). Returns (B, n, c). Equal to hypershape_data.grid_to_mesh."""
    d = points.shape[-1]
    g = points.flip(-1).to(values.dtype)  # grid_sample wants (x_last, ..., x_first)
    g = g.view(g.shape[0], *([1] * (d - 1)), g.shape[1], d)
    out = torch.nn.functional.grid_sample(values, g, mode="bilinear", padding_mode="border",
                                          align_corners=True)
    return out.flatten(2).transpose(1, 2)
