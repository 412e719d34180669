#!/usr/bin/env python3
"""Turn bench_shapes JSON files into a Markdown table (for the README).

    scripts/bench_shapes_table.py bench_shapes.json [more.json ...] > table.md

One row per preset (files concatenated in the order given): medians over the accepted shapes
of draw (deformation + boundary), mesh (gmsh + quality gate), metrics, the signed-distance grid
(build + evaluate), the patch distance on the same grid, the total (make_shape wall time with
its redraws + SDF grid + patch distance), and the sizes. Each file's machine note is printed
above the table; skipped presets, failed shapes and other notes below it. Standard library only.
"""
import argparse
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_table import fmt_time, fmt_int, table  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("files", nargs="+", help="JSON files written by bench_shapes --json")
    args = ap.parse_args()

    presets, notes, remarks = [], [], []
    for path in args.files:
        with open(path) as f:
            data = json.load(f)
        m, s = data["machine"], data["settings"]
        notes.append(
            f"- `{path}`: {m['hostname']}, {m['nproc']} cores, 1 rank, grids {s['grid2d']}^2 / "
            f"{s['grid3d']}^3, repeats {s['repeats']}, load average {m.get('load_average_start')} "
            f"-> {m.get('load_average_end')}, total {data.get('total_seconds', float('nan')):.1f} s, "
            f"{m['date_utc']}"
        )
        presets += data["presets"]
        for sk in data.get("skipped", []):
            remarks.append(f"- skipped `{sk['file']}`: {sk['reason']}")

    rows = []
    for p in presets:
        tag = [p["name"], p["dim"], p["h"]]
        if p.get("error"):
            rows.append(tag + [f"error: {p['error']}"] + [""] * 11)
            continue
        t, v = p["median_seconds"], p["median_values"]
        n_failed = len(p.get("samples_values", {}).get("failed_shape_id", []))
        rows.append(tag + [
            f"{p['repeats'] - n_failed}/{p['repeats']}",
            fmt_time(t.get("draw")), fmt_time(t.get("mesh")), fmt_time(t.get("metrics")),
            fmt_time(t.get("sdf_grid")), fmt_time(t.get("patch_grid")), fmt_time(t.get("total")),
            fmt_int(v.get("boundary_facets")), fmt_int(v.get("vertices")), fmt_int(v.get("cells")),
            fmt_int(v.get("redraws")),
        ])
        for n in p.get("notes", []):
            remarks.append(f"- {p['name']}: {n}")

    print("\n".join(notes))
    print()
    print(table(["preset", "dim", "h", "shapes ok", "draw", "mesh", "metrics", "SDF grid",
                 "patch distance", "total", "boundary facets", "vertices", "cells", "redraws"],
                rows))
    if remarks:
        print()
        print("\n".join(remarks))
    return 0


if __name__ == "__main__":
    sys.exit(main())
