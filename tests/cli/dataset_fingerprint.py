#!/usr/bin/env python3
"""A dataset's fingerprint: for every array of every shard (shard header attributes and the
stored config text aside), its shape, dtype, sum, sum of |x| and a strided sample of values.
Stored fingerprints of small preset runs made before a change hold the presets' datasets to
what they were (tests/cli/test_presets_unchanged.sh).

  dataset_fingerprint.py DIR > expected.json          write
  dataset_fingerprint.py DIR --check expected.json    compare (floats to --rtol, default 1e-9;
                                                      arrays the expectation lacks are new
                                                      channels and are listed, not failed)"""
import glob
import json
import os
import sys

import h5py
import numpy as np


def fingerprint(d):
    out = {}
    for shard in sorted(glob.glob(os.path.join(d, "shards", "*.h5"))):
        name = os.path.basename(shard)
        with h5py.File(shard, "r") as f:
            def visit(path, obj):
                if not isinstance(obj, h5py.Dataset):
                    return
                x = obj[()]
                if obj.dtype.kind in "SOU":
                    vals = [v.decode() if isinstance(v, bytes) else str(v) for v in np.ravel(x)]
                    out[f"{name}/{path}"] = {"text": vals}
                    return
                x = np.asarray(x, dtype=np.float64).ravel()
                fin = np.where(np.isfinite(x), x, 0.0)
                step = max(1, x.size // 16)
                out[f"{name}/{path}"] = {"shape": list(obj.shape), "dtype": str(obj.dtype),
                                         "sum": float(fin.sum()), "abs": float(np.abs(fin).sum()),
                                         "sample": [float(v) for v in fin[::step][:17]]}
            f.visititems(visit)
    return out


def close(a, b, rtol, scale):
    return abs(a - b) <= rtol * max(scale, 1e-300)


def check(got, want, rtol):
    errors, new = [], sorted(set(got) - set(want))
    for k, w in want.items():
        g = got.get(k)
        if g is None:
            errors.append(f"{k}: missing")
        elif "text" in w:
            if g.get("text") != w["text"]:
                errors.append(f"{k}: text differs")
        elif g.get("shape") != w["shape"] or g.get("dtype") != w["dtype"]:
            errors.append(f"{k}: shape/dtype {g.get('shape')} {g.get('dtype')} != {w['shape']} {w['dtype']}")
        else:
            scale = w["abs"]
            ok = close(g["sum"], w["sum"], rtol, scale) and close(g["abs"], w["abs"], rtol, scale)
            ok = ok and all(close(x, y, rtol, scale) for x, y in zip(g["sample"], w["sample"]))
            if not ok:
                errors.append(f"{k}: values differ (sum {g['sum']!r} vs {w['sum']!r})")
    return errors, new


def main(argv):
    d = argv[1]
    got = fingerprint(d)
    if "--check" not in argv:
        json.dump(got, sys.stdout, indent=0, sort_keys=True)
        return 0
    want = json.load(open(argv[argv.index("--check") + 1]))
    rtol = float(argv[argv.index("--rtol") + 1]) if "--rtol" in argv else 1e-9
    errors, new = check(got, want, rtol)
    for e in errors[:20]:
        print("DIFF", e)
    if new:
        print(f"{len(new)} new arrays (not in the expectation): {new[:8]}")
    print(f"{len(want)} arrays expected, {len(errors)} differ")
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
