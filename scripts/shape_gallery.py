#!/usr/bin/python3
"""Galleries and metric histograms of shape files written by `hypershape shapes`.

    scripts/shape_gallery.py SHAPES.h5 [MORE.h5 ...] [--out-dir docs/figures] [--max 16]

For every file (root attribute `name` = NAME) it writes

  OUT_DIR/NAME_gallery.png    the first (up to) 16 shapes in a 4x4 grid (fewer panels if the
                              file holds fewer shapes)
      2D: the filled boundary polygon, the Dirichlet patch facets drawn thick in another
          colour and p_D as a dot; axes [-1.05, 1.05]^2, equal aspect; title "id, iso ratio".
      3D: the boundary surface (Poly3DCollection; each triangle lit by the mean of its vertex
          normals, so the shading follows the surface rather than the facets), the Dirichlet
          patch facets in another colour, seen from p_D's side (30 degrees off, so the patch
          is in view); box [-1, 1]^3; title "id, Hausdorff distance to the base".
      A failed shape (attribute failed == 1) is an empty panel labelled "failed".
  OUT_DIR/NAME_histogram.png  the isoperimetric ratio (2D) / the Hausdorff distance to the base
                              (3D) over ALL non-failed shapes in the file (not written for one
                              shape: OneRandom2D)

and prints one summary line per file: shapes, failed, redraws, median/min/max of the metric.
Needs h5py, numpy and matplotlib (Agg backend, no display).
"""
import argparse
import os
import re
import sys

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402

BODY = "#9ecae1"       # shape fill (2D) / surface (3D)
EDGE = "#3182bd"       # 2D boundary line
PATCH = "#d62728"      # Dirichlet patch facets
CENTER = "#000000"     # p_D


def text_attr(v):
    if isinstance(v, bytes):
        return v.decode()
    if isinstance(v, np.ndarray):
        return text_attr(v.item() if v.size == 1 else v.tolist())
    return str(v)


def load(path):
    """The file's header and one dict per shape (id order)."""
    shapes = []
    with h5py.File(path, "r") as f:
        name = text_attr(f.attrs.get("name", os.path.splitext(os.path.basename(path))[0]))
        dim = int(f.attrs.get("dim", 0))
        for key in sorted(f["shapes"].keys()):
            g = f["shapes"][key]
            a = {k: g.attrs[k] for k in g.attrs}
            s = {
                "id": int(a.get("shape_id", int(key))),
                "failed": bool(a.get("failed", 0)),
                "attrs": a,
                "rejected": text_attr(g["rejected"][()]) if "rejected" in g else "",
            }
            for ds in ("boundary/points", "boundary/facets", "dirichlet_facets"):
                s[ds] = g[ds][()] if ds in g else np.zeros((0,))
            shapes.append(s)
    if not dim:
        dim = next((s["boundary/points"].shape[1] for s in shapes if s["boundary/points"].ndim == 2
                    and s["boundary/points"].shape[0]), 2)
    return name, dim, shapes


def rejected_stages(s):
    """The stage of each rejected draw of a shape, from its `rejected` text: lines
    "ATTEMPT STAGE: reason" (shape files) or "attempt ATTEMPT (STAGE): reason" (error messages)."""
    text = s["rejected"]
    stages = re.findall(r"^\s*\d+ (\w+): ", text, flags=re.M)
    return stages or re.findall(r"attempt \d+ \((\w+)\)", text)


def redraws(s):
    """Rejected draws of a shape: n_rejected, or the lines of `rejected` for a failed one."""
    if "n_rejected" in s["attrs"]:
        return int(s["attrs"]["n_rejected"])
    return len(rejected_stages(s))


def metric(s, dim):
    key = "isoperimetric_ratio" if dim == 2 else "hausdorff_to_base"
    v = s["attrs"].get(key, np.nan)
    return float(v)


def failed_panel(ax, s):
    ax.set_axis_off()
    # The stages of its rejected draws, e.g. "20 draws: feature 18, quality 2".
    stages = rejected_stages(s)
    detail = ", ".join(f"{k} {stages.count(k)}" for k in sorted(set(stages), key=stages.index))
    text = "failed" + (f"\n{len(stages)} draws: {detail}" if stages else "")
    put = getattr(ax, "text2D", ax.text)  # 3D axes take 2D text through text2D
    put(0.5, 0.5, text, ha="center", va="center", transform=ax.transAxes, fontsize=10,
        color=PATCH)
    ax.set_title(f"#{s['id']}", fontsize=8)


def draw_2d(ax, s):
    pts, fac = s["boundary/points"], s["boundary/facets"].astype(int)
    # The facets are CCW segments (a, b) of one closed polygon: walk them in order.
    nxt = dict(zip(fac[:, 0], fac[:, 1]))
    order, v = [fac[0, 0]], nxt[fac[0, 0]]
    while v != order[0] and len(order) <= len(fac):
        order.append(v)
        v = nxt[v]
    poly = pts[order]
    ax.fill(poly[:, 0], poly[:, 1], color=BODY, lw=0)
    ax.plot(*np.vstack([poly, poly[:1]]).T, color=EDGE, lw=0.6)
    dfac = s["dirichlet_facets"].astype(int)
    if dfac.size:
        segs = pts[fac[dfac]]  # k x 2 x 2
        for seg in segs:
            ax.plot(seg[:, 0], seg[:, 1], color=PATCH, lw=2.6, solid_capstyle="round")
    c = np.asarray(s["attrs"].get("dirichlet_center", [np.nan] * 3), dtype=float)
    if s["attrs"].get("dirichlet_radius", 0) > 0:
        ax.plot(c[0], c[1], "o", color=CENTER, ms=3.5)
    ax.set_xlim(-1.05, 1.05)
    ax.set_ylim(-1.05, 1.05)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])
    for sp in ax.spines.values():
        sp.set_color("#bbbbbb")
    ax.set_title(f"#{s['id']}  iso {metric(s, 2):.3f}", fontsize=8)


def shade(rgb, normals, light):
    lam = np.clip(normals @ light, 0.0, 1.0)
    base = np.asarray(matplotlib.colors.to_rgb(rgb))[None, :]
    return np.clip(base * (0.35 + 0.65 * lam[:, None]), 0, 1)


def smooth_normals(pts, fac):
    """Per triangle, the mean of its three vertex normals (area-weighted facet normals around
    each vertex): lighting with these shades the surface the triangles sample rather than the
    facets (the boundary is resolved at h, so flat shading shows mostly the triangulation)."""
    tri = pts[fac]
    fn = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])  # 2 * area * unit normal
    vn = np.zeros_like(pts)
    for k in range(3):
        np.add.at(vn, fac[:, k], fn)
    vn /= np.maximum(np.linalg.norm(vn, axis=1, keepdims=True), 1e-300)
    n = vn[fac].mean(axis=1)
    return n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)


def draw_3d(ax, s):
    pts, fac = s["boundary/points"], s["boundary/facets"].astype(int)
    tri = pts[fac]  # m x 3 x 3
    n = smooth_normals(pts, fac)
    # Look at the shape from p_D's side, lit from the camera and above.
    c = np.asarray(s["attrs"].get("dirichlet_center", [0.0, 0.0, 0.0]), dtype=float)
    has_patch = s["attrs"].get("dirichlet_radius", 0) > 0 and np.linalg.norm(c) > 1e-9
    if has_patch:
        u = c / np.linalg.norm(c)
        azim, elev = np.degrees(np.arctan2(u[1], u[0])), np.degrees(np.arcsin(np.clip(u[2], -1, 1)))
        # 30 degrees off p_D's direction: the patch in view, the silhouette still telling.
        azim, elev = azim + 30.0, float(np.clip(elev + 15.0, -60.0, 60.0))
    else:
        azim, elev = -60.0, 20.0
    a, e = np.radians(azim), np.radians(elev)
    eye = np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])
    light = eye + 0.5 * np.array([0.0, 0.0, 1.0]) - 0.3 * np.array([-np.sin(a), np.cos(a), 0.0])
    light /= np.linalg.norm(light)
    colors = shade(BODY, n, light)
    dfac = s["dirichlet_facets"].astype(int)
    if dfac.size:
        colors[dfac] = shade(PATCH, n[dfac], light)
    # Edges in the face colour hide the anti-aliasing seams between triangles.
    coll = Poly3DCollection(tri, facecolors=colors, edgecolors=colors, linewidths=0.2)
    ax.add_collection3d(coll)
    for set_lim in (ax.set_xlim, ax.set_ylim, ax.set_zlim):
        set_lim(-1.0, 1.0)
    ax.set_box_aspect((1, 1, 1), zoom=1.35)
    ax.view_init(elev=elev, azim=azim)
    ax.set_axis_off()
    ax.set_title(f"#{s['id']}  Hausdorff {metric(s, 3):.3f}", fontsize=8)


def gallery(name, dim, shapes, path, n_max):
    shown = shapes[:n_max]
    cols = min(4, len(shown))
    rows = -(-len(shown) // cols)
    fig = plt.figure(figsize=(3.0 * cols, 3.15 * rows + 0.45))
    for i in range(len(shown)):
        if dim == 3:
            ax = fig.add_subplot(rows, cols, i + 1, projection="3d")
        else:
            ax = fig.add_subplot(rows, cols, i + 1)
        s = shown[i]
        if s["failed"] or s["boundary/points"].size == 0:
            failed_panel(ax, s)
        elif dim == 2:
            draw_2d(ax, s)
        else:
            draw_3d(ax, s)
    ids = (f"shapes {shown[0]['id']}..{shown[-1]['id']}" if len(shown) > 1
           else f"shape {shown[0]['id']}")
    what = "Dirichlet patch red" + (", p_D dot" if dim == 2 else "") if cols > 1 else "patch red"
    fig.suptitle(f"{name}: {ids} ({what})", fontsize=12 if cols > 1 else 9)
    fig.tight_layout(rect=(0, 0, 1, 1 - 0.45 / (3.15 * rows + 0.45)))
    fig.savefig(path, dpi=90)
    plt.close(fig)


def histogram(name, dim, values, path):
    label = "isoperimetric ratio 4πA/P²" if dim == 2 else "Hausdorff distance to the base"
    fig, ax = plt.subplots(figsize=(6, 4))
    if values.size:
        ax.hist(values, bins=min(40, max(5, int(np.sqrt(values.size)) * 2)), color=BODY,
                edgecolor=EDGE)
        ax.axvline(np.median(values), color=PATCH, lw=1.5, label=f"median {np.median(values):.3f}")
        ax.legend(fontsize=9)
    ax.set_xlabel(label)
    ax.set_ylabel("shapes")
    ax.set_title(f"{name}: {label} over {values.size} shapes", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("files", nargs="+", help="shape files (.h5) written by `hypershape shapes`")
    ap.add_argument("--out-dir", default="docs/figures", help="where the PNGs go (default: %(default)s)")
    ap.add_argument("--max", type=int, default=16, help="shapes in the gallery (at most 16)")
    args = ap.parse_args()
    os.makedirs(args.out_dir, exist_ok=True)
    n_max = max(1, min(16, args.max))
    for path in args.files:
        name, dim, shapes = load(path)
        if not shapes:
            print(f"{name}: {path} holds no shapes", file=sys.stderr)
            continue
        ok = [s for s in shapes if not s["failed"]]
        values = np.array([metric(s, dim) for s in ok])
        values = values[np.isfinite(values)]
        g = os.path.join(args.out_dir, f"{name}_gallery.png")
        h = os.path.join(args.out_dir, f"{name}_histogram.png")
        gallery(name, dim, shapes, g, n_max)
        if values.size > 1:  # a histogram of one shape says nothing
            histogram(name, dim, values, h)
        else:
            h = "no histogram (one shape)"
        mname = "iso ratio" if dim == 2 else "Hausdorff"
        stats = (f"{mname} median {np.median(values):.4f} min {values.min():.4f} "
                 f"max {values.max():.4f}") if values.size else f"{mname}: none"
        n_redraws = sum(redraws(s) for s in shapes)
        print(f"{name} ({dim}D): {len(shapes)} shapes, {len(shapes) - len(ok)} failed, "
              f"{n_redraws} redraws | {stats} -> {g}, {h}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
