"""The XDMF views of a dataset (docs/FORMAT.md, "XDMF views"), read by meshio (Debian's
python3-meshio) as a person would, on a 2D P1 dataset of 2 shards and a 3D P2 one:
  - no HyperSlab anywhere (ParaView's default reader drops such attributes);
  - every xdmf/shape-*.xdmf through meshio's TimeSeriesReader: the mesh, one time step per load
    case, and at each step sdf, dirichlet_distance, both masks, displacement and traction with
    the shard's shapes and values (tests/python/xdmf_readers.py; ParaView's readers on the same
    files: tests/tools/test_paraview.sh, opt-in);
  - the companion xdmf/shard-*.h5 holds virtual datasets only (nothing copied: a fraction of the
    shard's size), and still reads after the dataset directory is moved (relative paths).
Needs HYPERSHAPE_BIN and HYPERSHAPE_SOURCE_DIR (set by CTest)."""
import glob
import os
import shutil
import subprocess
import sys
import tempfile

import h5py

src = os.environ["HYPERSHAPE_SOURCE_DIR"]
bin_ = os.environ["HYPERSHAPE_BIN"]
sys.path.insert(0, os.path.join(src, "tests", "python"))
import xdmf_readers as xr  # noqa: E402

CONFIGS = {
    "x2d": "preset: random2d_p1\nname: x2d\nseed: 5\nshapes: {count: 3, h: 0.1}\nloads: {count: 3}\n"
           "representations: {grid_size: 8}\noutput: {shard_size: 2}\n",
    "x3d": "preset: random3d\nname: x3d\nseed: 7\nshapes: {count: 1}\nloads: {count: 2}\n"
           "representations: {grid_size: 8}\n",
}


def check_views_file(d):
    for path in sorted(glob.glob(os.path.join(d, "xdmf", "shard-*.h5"))):
        views = []
        with h5py.File(path, "r") as f:
            f.visititems(lambda n, o: views.append(o.is_virtual) if isinstance(o, h5py.Dataset) else None)
        shard = os.path.join(d, "shards", os.path.basename(path))
        size, shard_size = os.path.getsize(path), os.path.getsize(shard)
        xr.check(views and all(views) and size < 0.25 * shard_size,
                 f"{os.path.basename(path)}: {len(views)} datasets, all virtual, {size} bytes (shard {shard_size})")


def main():
    tmp = tempfile.mkdtemp()
    try:
        for name, text in CONFIGS.items():
            cfg = os.path.join(tmp, f"{name}.yaml")
            open(cfg, "w").write(text)
            d = os.path.join(tmp, name)
            subprocess.run([bin_, "-q", "generate", cfg, "--progress", "0", "-o", d], check=True)
            xr.check_no_hyperslab(d)
            check_views_file(d)
            xr.check_meshio(d)
        moved = os.path.join(tmp, "elsewhere", "x2d")
        shutil.move(os.path.join(tmp, "x2d"), moved)
        os.chdir(os.path.join(tmp, "elsewhere"))
        n = xr.checks.failures
        xr.check_meshio(moved)
        xr.check(xr.checks.failures == n, "the moved dataset reads the same from another directory")
    finally:
        shutil.rmtree(tmp)
    print(f"{'ok' if xr.checks.failures == 0 else 'FAILED'}: {xr.checks.failures} failures")
    return 1 if xr.checks.failures else 0


if __name__ == "__main__":
    sys.exit(main())
