"""Opens a dataset's XDMF views (docs/FORMAT.md, "XDMF views") with real readers and compares
every array they return with the shards, read by h5py:

    /usr/bin/python3 tests/python/xdmf_readers.py meshio DIR     # xdmf/shape-*.xdmf, TimeSeriesReader
    /usr/bin/python3 tests/python/xdmf_readers.py paraview DIR   # xdmf/shard-*.xdmf and shape-*.xdmf,
                                                                 # ParaView's default reader and the legacy one

Each check prints "ok ..." / "FAIL ..." lines and the module's `checks.failures` counts the failures;
the command exits 1 if any failed. What is asserted, per reader and file: the reader's name
(ParaView's default must be Xdmf3ReaderS), one time step per load case (times 0..L-1), and at
every time step, for every solved shape, the arrays sdf, dirichlet_distance, dirichlet_mask,
neumann_mask, displacement and traction (where the shard has them) with their shapes (n,) or
(n, d) and their values equal to the shard's (displacement and traction of that load case).
"""
import glob
import os
import re
import sys

import h5py
import numpy as np

SCALARS = {"sdf": "point_cloud/sdf", "dirichlet_distance": "point_cloud/dirichlet_distance",
           "dirichlet_mask": "dirichlet_mask", "neumann_mask": "neumann_mask"}
LOAD_FIELDS = ("displacement", "traction")
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import checks  # noqa: E402
from checks import check  # noqa: E402


def shard_of(xdmf):
    """The shard a shard-NNNNNN.xdmf or shape-IIIIII.xdmf refers to (its Geometry's file)."""
    text = open(xdmf).read()
    rel = re.search(r">([^<>:]+\.h5):/shapes/\d+/nodes<", text).group(1)
    return os.path.normpath(os.path.join(os.path.dirname(xdmf), rel))


def expected(shard, shape_ids=None):
    """{shape id: {"nodes": .., "cells": .., name: array, field: (L, n, d) array}} of the solved shapes."""
    out = {}
    with h5py.File(shard, "r") as f:
        for name, g in sorted(f["shapes"].items()):
            if "nodes" not in g or (shape_ids is not None and name not in shape_ids):
                continue
            e = {"nodes": g["nodes"][()], "cells": g["cells"][()]}
            for key, path in SCALARS.items():
                if path in g:
                    e[key] = g[path][()]
            for field in LOAD_FIELDS:
                if f"loads/{field}" in g:
                    e[field] = g[f"loads/{field}"][()]
            out[name] = e
    return out


def n_loads(exp):
    return next(iter(exp.values()))["displacement"].shape[0]


def compare(label, got, e, l):
    """got: {array name: numpy array} of one shape at load case l; e: expected()[shape]."""
    names = [k for k in list(SCALARS) + list(LOAD_FIELDS) if k in e]
    if not check(sorted(names) == sorted(k for k in got if k in names) and all(k in got for k in names),
                 f"{label}: arrays {sorted(names)} (reader gave {sorted(got)})"):
        return
    bad = []
    for k in names:
        want = e[k][l] if k in LOAD_FIELDS else e[k]
        have = np.asarray(got[k])
        if have.ndim == 2 and want.ndim == 2 and have.shape[1] == 3 and want.shape[1] == 2:
            bad += [f"{k} z" for _ in [0] if np.any(have[:, 2] != 0)]
            have = have[:, :2]  # a 2D vector padded to 3 components by VTK
        if have.reshape(want.shape if have.size == want.size else have.shape).shape != want.shape:
            bad.append(f"{k} shape {have.shape} != {want.shape}")
        elif not np.allclose(have.reshape(want.shape), want, rtol=0, atol=1e-12 * (1 + np.abs(want).max())):
            bad.append(f"{k} values")
    check(not bad, f"{label}: shapes and values of {len(names)} arrays" + (f" ({', '.join(bad)})" if bad else ""))


# ---- meshio ---------------------------------------------------------------------------------
def check_meshio(dataset):
    import meshio
    files = sorted(glob.glob(os.path.join(dataset, "xdmf", "shape-*.xdmf")))
    check(len(files) > 0, f"meshio: {len(files)} shape-*.xdmf files in {dataset}/xdmf")
    for path in files:
        sid = re.search(r"shape-(\d+)\.xdmf$", path).group(1)
        e = expected(shard_of(path), {sid})[sid]
        with meshio.xdmf.TimeSeriesReader(path) as r:
            points, cells = r.read_points_cells()
            check(np.array_equal(points, e["nodes"]) and np.array_equal(cells[0].data, e["cells"]),
                  f"meshio {os.path.basename(path)}: {len(points)} points, {len(cells[0].data)} {cells[0].type} cells")
            L = e["displacement"].shape[0]
            check(r.num_steps == L, f"meshio {os.path.basename(path)}: {r.num_steps} time steps (load cases: {L})")
            for k in range(r.num_steps):
                t, point_data, _ = r.read_data(k)
                check(t == k, f"meshio {os.path.basename(path)} step {k}: time {t}")
                compare(f"meshio {os.path.basename(path)} step {k}", point_data, e, k)


# ---- ParaView -------------------------------------------------------------------------------
def _blocks(data):
    """(name, vtkDataSet) of every leaf of a composite data set, in order."""
    from paraview.vtk import vtkCompositeDataSet
    if not data.IsA("vtkCompositeDataSet"):
        return [("", data)]
    out, it = [], data.NewIterator()
    it.InitTraversal()
    while not it.IsDoneWithTraversal():
        meta = it.GetCurrentMetaData()
        out.append((meta.Get(vtkCompositeDataSet.NAME()) or "", it.GetCurrentDataObject()))
        it.GoToNextItem()
    return out


def _point_arrays(block):
    from vtkmodules.util.numpy_support import vtk_to_numpy
    pd = block.GetPointData()
    return {pd.GetArrayName(i): vtk_to_numpy(pd.GetArray(i)) for i in range(pd.GetNumberOfArrays())}


def _read_paraview(reader, exp, label):
    from paraview import servermanager as sm
    times = list(reader.TimestepValues) if reader.TimestepValues else [0.0]
    L = n_loads(exp)
    check(times == [float(l) for l in range(L)], f"{label}: time steps {times} (load cases 0..{L - 1})")
    for l, t in enumerate(times):
        reader.UpdatePipeline(t)
        blocks = _blocks(sm.Fetch(reader))
        check(len(blocks) == len(exp), f"{label} t={t}: {len(blocks)} blocks for {len(exp)} solved shapes")
        for (name, block), (sid, e) in zip(blocks, exp.items()):
            ok = block.GetNumberOfPoints() == len(e["nodes"]) and block.GetNumberOfCells() == len(e["cells"])
            check(ok, f"{label} t={t} shape {sid} ({name}): {block.GetNumberOfPoints()} points, "
                      f"{block.GetNumberOfCells()} cells")
            compare(f"{label} t={t} shape {sid}", _point_arrays(block), e, l)


def check_paraview(dataset):
    from paraview import simple as pv
    shards = sorted(glob.glob(os.path.join(dataset, "xdmf", "shard-*.xdmf")))
    shapes = sorted(glob.glob(os.path.join(dataset, "xdmf", "shape-*.xdmf")))
    check(len(shards) > 0 and len(shapes) > 0, f"paraview: {len(shards)} shard and {len(shapes)} shape XDMF files")
    for path in shards + shapes[:1]:
        sid = re.search(r"shape-(\d+)\.xdmf$", path)
        exp = expected(shard_of(path), {sid.group(1)} if sid else None)
        reader = pv.OpenDataFile(path)
        check(reader.GetXMLName() == "Xdmf3ReaderS", f"OpenDataFile({os.path.basename(path)}) picks "
                                                     f"{reader.GetXMLName()} (ParaView's default for .xdmf)")
        _read_paraview(reader, exp, f"{reader.GetXMLName()} {os.path.basename(path)}")
        pv.Delete(reader)
        legacy = pv.XDMFReader(FileNames=[path])
        _read_paraview(legacy, exp, f"XDMFReader (legacy) {os.path.basename(path)}")
        pv.Delete(legacy)


def check_no_hyperslab(dataset):
    files = glob.glob(os.path.join(dataset, "xdmf", "*.xdmf"))
    bad = [f for f in files if "HyperSlab" in open(f).read()]
    check(files and not bad, f"{len(files)} XDMF files, none with a HyperSlab DataItem {bad[:3]}")


if __name__ == "__main__":
    which, dataset = sys.argv[1], sys.argv[2]
    check_no_hyperslab(dataset)
    {"meshio": check_meshio, "paraview": check_paraview}[which](dataset)
    print(f"xdmf_readers {which}: {'ok' if checks.failures == 0 else f'{checks.failures} failures'}")
    sys.exit(1 if checks.failures else 0)
