#!/usr/bin/python3
"""Pictures of solutions in a dataset made by `hypershape generate` (matplotlib; used by
`scripts/hypershape_data.py plot`):

    scripts/hypershape_data.py plot DIR [--shape I ...] [--load J ...] [-o out.png] [--cols C] [--scale S]

One panel per (shape, load case): the deformed body x + S u coloured by |u| (2D: tripcolor on
the deformed mesh, P2 triangles split in four at their edge nodes; 3D: the boundary triangles
of the deformed mesh in a Poly3DCollection, each coloured by the mean |u| of its corners and
shaded by its normal), the undeformed outline (2D, dashed grey), the Dirichlet patch (red),
each active Gaussian traction: its centre p_N (moved with the body) and its direction g (arrow),
and the region of a `pressure` (where its channel is not zero: white dots at the boundary
vertices in 3D, a dotted black line in 2D).
The title gives the shape, load case, achieved max|u|, target and alpha (or why it failed), and
the pressure p drawn for the load case.
"""
import math

import numpy as np

PATCH_COLOUR, LOAD_COLOUR, PRESSURE_COLOUR = "#d62728", "#ff7f0e", "white"


# ---- mesh pieces --------------------------------------------------------------------------
def _corners(cells, dim):
    return cells[:, : dim + 1]


def _edge_midpoints(cells, dim):
    """{(a, b) sorted: node id of the edge's midpoint} of P2 cells (VTK order), else {}."""
    local = {6: [(0, 1), (1, 2), (2, 0)], 10: [(0, 1), (1, 2), (0, 2), (0, 3), (1, 3), (2, 3)]}
    pairs = local.get(cells.shape[1])
    if pairs is None:
        return {}
    mids = {}
    for e, (i, j) in enumerate(pairs):
        a, b = np.minimum(cells[:, i], cells[:, j]), np.maximum(cells[:, i], cells[:, j])
        mids.update(zip(zip(a.tolist(), b.tolist()), cells[:, dim + 1 + e].tolist()))
    return mids


def _split_p2(tris, mids):
    """Each triangle (a, b, c) into four at its edge midpoints (P2), or unchanged (P1)."""
    if not mids:
        return tris
    m = lambda a, b: np.array([mids[(min(x, y), max(x, y))] for x, y in zip(a, b)])  # noqa: E731
    a, b, c = tris.T
    ab, bc, ca = m(a, b), m(b, c), m(c, a)
    return np.concatenate([np.c_[a, ab, ca], np.c_[ab, b, bc], np.c_[ca, bc, c], np.c_[ab, bc, ca]])


def _boundary(cells, dim):
    """Boundary facets (edges in 2D, triangles in 3D) of the corner mesh: those in one cell only."""
    c = _corners(cells, dim)
    local = [(0, 1), (1, 2), (2, 0)] if dim == 2 else [(0, 1, 2), (0, 1, 3), (0, 2, 3), (1, 2, 3)]
    facets = np.concatenate([c[:, list(f)] for f in local])
    _, first, counts = np.unique(np.sort(facets, axis=1), axis=0, return_index=True, return_counts=True)
    return facets[first[counts == 1]]


# ---- what is drawn on top -----------------------------------------------------------------
def _loads(sample):
    """[(p_N, g)] of the active Gaussian tractions of a sample (the first from loads/p_n, g)."""
    out = [] if sample.p_n is None else [(np.asarray(sample.p_n), np.asarray(sample.g))]
    count = sample.params.get("gaussian_traction/count", math.inf)
    for k in range(1, 16):
        c = sample.params.get(f"gaussian_traction.{k}/center")
        if c is None:
            break
        if k < count:
            out.append((np.asarray(c), np.asarray(sample.params[f"gaussian_traction.{k}/direction"])))
    return out


def _pressed(sample):
    """Boolean per node: where the sample's pressure channel acts (all False without one)."""
    p = sample.point_cloud.get("pressure") if sample.point_cloud else None
    return np.zeros(len(sample.nodes), bool) if p is None else p[:, 0] != 0


def _moved(point, nodes, u):
    """A reference point moved with the body (by the displacement of its nearest node)."""
    return point + u[np.argmin(np.sum((nodes - point) ** 2, axis=1))]


def _title(sample):
    head = f"shape {sample.shape_id}, load {sample.load_id}"
    if sample.status != 1:
        return f"{head}: FAILED\n{sample.reason[:60]}"
    p = sample.params.get("pressure/value")
    tail = "" if p is None or np.ndim(p) else f", p {float(p):.3g}"
    return f"{head}\nmax|u| {sample.max_displacement:.3f} (target {sample.target:.3f}), alpha {sample.alpha:.3g}{tail}"


# ---- panels -------------------------------------------------------------------------------
def draw_2d(ax, sample, scale=1.0):
    from matplotlib.collections import LineCollection
    u = sample.displacement
    x, mag = sample.nodes + scale * u, np.linalg.norm(u, axis=1)
    tris = _split_p2(_corners(sample.cells, 2), _edge_midpoints(sample.cells, 2))
    art = ax.tripcolor(x[:, 0], x[:, 1], tris, mag, shading="gouraud", cmap="viridis", vmin=0)
    edges = _boundary(sample.cells, 2)
    ax.add_collection(LineCollection(sample.nodes[edges], colors="0.5", linewidths=0.8, linestyles="--"))
    patch = edges[sample.dirichlet_mask[edges].all(axis=1)]
    ax.add_collection(LineCollection(x[patch], colors=PATCH_COLOUR, linewidths=3))
    pressed = edges[_pressed(sample)[edges].all(axis=1)]
    ax.add_collection(LineCollection(x[pressed], colors="k", linewidths=1.5, linestyles=":"))
    for p, g in _loads(sample):
        q = _moved(p, sample.nodes, scale * u)
        ax.plot(*q, "o", color=LOAD_COLOUR, ms=5, mec="k", mew=0.5)
        ax.annotate("", xy=q + 0.45 * g, xytext=q,
                    arrowprops=dict(arrowstyle="-|>", color=LOAD_COLOUR, lw=2, mutation_scale=14))
    ax.set_aspect("equal")
    ax.set_xlim(-1.5, 1.5), ax.set_ylim(-1.5, 1.5)
    ax.set_xticks([]), ax.set_yticks([])
    return art


def _shade(verts, colours):
    """Lambert-like shading: faces turned away from the light are darker (sign ignored)."""
    n = np.cross(verts[:, 1] - verts[:, 0], verts[:, 2] - verts[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    light = np.array([0.4, -0.5, 0.77])
    f = 0.55 + 0.45 * np.abs(n @ (light / np.linalg.norm(light)))
    out = colours.copy()
    out[:, :3] *= f[:, None]
    return out


def _look_at(ax, points):
    """Puts the camera on the side of the mean direction of `points` (the load, the patch)."""
    units = [p / max(np.linalg.norm(p), 1e-12) for p in points]
    v = np.sum(units, axis=0) if units else np.array([1.0, -1.0, 0.5])
    if np.linalg.norm(v) < 0.3:  # on opposite sides: show the load
        v = units[0]
    elev = math.degrees(math.atan2(v[2], math.hypot(v[0], v[1])))
    ax.view_init(elev=float(np.clip(elev, -50, 50)), azim=math.degrees(math.atan2(v[1], v[0])))


def draw_3d(ax, sample, scale=1.0):
    import matplotlib as mpl
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection
    u = sample.displacement
    x, mag = sample.nodes + scale * u, np.linalg.norm(u, axis=1)
    corner_faces = _boundary(sample.cells, 3)
    faces = _split_p2(corner_faces, _edge_midpoints(sample.cells, 3))
    norm = mpl.colors.Normalize(vmin=0, vmax=max(mag.max(), 1e-12))
    colours = _shade(x[faces], mpl.colormaps["viridis"](norm(mag[faces].mean(axis=1))))
    ax.computed_zorder = False  # the patch and the loads drawn over the surface
    ax.add_collection3d(Poly3DCollection(x[faces], facecolors=colours, edgecolors="none", zorder=1))
    on_surface = np.unique(faces)
    patch = on_surface[sample.dirichlet_mask[on_surface]]
    ax.scatter(*x[patch].T, s=2, color=PATCH_COLOUR, depthshade=False, zorder=2)
    corners = np.unique(corner_faces)  # vertices only: P2 edge nodes would crowd
    pressed = corners[_pressed(sample)[corners]]
    ax.scatter(*x[pressed].T, s=5, color=PRESSURE_COLOUR, edgecolors="k", linewidths=0.3, depthshade=False, zorder=2)
    loads = _loads(sample)
    for p, g in loads:
        q = _moved(p, sample.nodes, scale * u)
        ax.scatter(*q, s=30, color=LOAD_COLOUR, edgecolors="k", depthshade=False, zorder=3)
        ax.quiver(*q, *g, length=0.6, color=LOAD_COLOUR, linewidth=2, arrow_length_ratio=0.3, zorder=3)
    _look_at(ax, [p for p, _ in loads[:1]] + [x[v].mean(axis=0) for v in (patch, pressed) if len(v)])
    for set_lim in (ax.set_xlim, ax.set_ylim, ax.set_zlim):
        set_lim(-1, 1)
    ax.set_box_aspect((1, 1, 1), zoom=1.35)
    ax.set_axis_off()
    return mpl.cm.ScalarMappable(norm=norm, cmap="viridis")


def plot(dataset, pairs, out, cols=None, scale=1.0):
    """Writes `out` (PNG): one panel per (shape id, load id) of `pairs` from the Dataset."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    cols = cols or min(len(pairs), 4)
    rows = -(-len(pairs) // cols)
    fig = plt.figure(figsize=(3.6 * cols, 3.5 * rows), dpi=110)
    for i, (sid, lid) in enumerate(pairs):
        s = dataset.sample(sid, lid, grid=False)
        ax = fig.add_subplot(rows, cols, i + 1, projection="3d" if s.dim == 3 else None)
        art = (draw_3d if s.dim == 3 else draw_2d)(ax, s, scale)
        fig.colorbar(art, ax=ax, shrink=0.7, pad=0.02, label="|u|")
        ax.set_title(_title(s), fontsize=8)
    pressure = "; pressure region white dots" if "pressure" in dataset.channels else ""
    fig.suptitle(f"{dataset.name}: deformed shape coloured by |u|; Dirichlet patch red, "
                 f"traction centre and direction orange{pressure}" + (f"; u x {scale:g}" if scale != 1 else ""),
                 fontsize=9)
    fig.tight_layout()
    fig.savefig(out)
    plt.close(fig)
