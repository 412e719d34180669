#!/usr/bin/python3
"""Synthetic, liver-like closed surfaces: the base of the aug_liver preset and the stand-in
shape directory of the liver / one_liver presets.

    scripts/make_organ_surface.py [--out configs/surfaces/organ.stl] [--level 4] [--seed 0]
    scripts/make_organ_surface.py --livers configs/surfaces/livers [--count 5] [--level 3]

The first form writes one surface: seed 0 (the default) is the organ of aug_liver; another seed
varies its lobes (see "Variation"). The second writes --count surfaces liver_000.stl, ...
made with seeds 1, 2, ..., skipping a seed whose surface has a triangle angle below 12 deg or a
normal turn across an edge above 65 deg (rays there graze the surface, or a crease is too sharp):
the stand-ins for the seed paper's 92 Liver segmentations. configs/surfaces/livers/ holds the
default 5 (seeds 1, 2, 3, 5, 6; level 3: 1280 triangles, 64 KB each).

The seed paper's AugLiver deforms a real liver surface (a segmentation of the LiTS data, CC
BY-NC-ND); none can be downloaded here, so this script makes a stand-in with the features that
matter to the shape family: elongated (about 2 : 1.3 : 1), asymmetric, a large, thick right lobe
and a smaller, thinner left lobe that tapers to the left, a small caudate bulge at the back, a
domed upper side and a flatter lower side. It is NOT anatomical data.

Construction (numpy only, deterministic):
  * the solid is the level set F = 0 of a smooth maximum (log-sum-exp, sharpness K) of four
    ellipsoid functions 1 - |R (x - c) / a|^2 (right lobe, left lobe, caudate lobe, a bridge
    between the lobes), smoothly intersected with a half-space that flattens the lower side;
    units are centimetres, but any units do: the pipeline rescales the base into [-1, 1]^3;
  * every ellipsoid and the half-space contain the centre C, so the solid is star-shaped about
    C; the surface is the radial graph x(u) = C + r(u) u over the directions u of an icosphere
    (level --level: 10 * 4^level + 2 points, 20 * 4^level triangles), r(u) found by bisection
    along each ray, and a radial graph over a sphere triangulation is a closed, embedded
    2-manifold (it cannot self-intersect);
  * the icosphere's directions are first stretched by the solid's half-extents (u = normalise(E
    v)), which spreads the points evenly over the elongated solid instead of crowding the near
    right lobe; C sits at the waist between the lobes, where no ray grazes the surface (smallest
    triangle angle 20 deg, edges within a factor 6 of each other).

Variation (seed S > 0, deterministic: numpy's default_rng(S)): every lobe centre moves by
N(0, 0.4 cm) per axis, its semi-axes are scaled by exp(N(0, 0.1)) and its rotation angles move by
N(0, 5 deg); the flattening plane tilts by N(0, 4 deg) and moves by N(0, 0.4 cm); the whole organ is
stretched by exp(N(0, 0.08)) per axis. These are livers of one family (same lobes, different
proportions), as segmentations of different patients are; still not anatomical data.

The script checks (and fails loudly otherwise) that each ray crosses the surface exactly once,
that the triangles are outward, and reports the edge lengths, smallest angle and largest dihedral
angle between neighbouring triangles (smoothness). Writes binary STL.
"""
import argparse
import os
import struct
import sys

import numpy as np

# Smooth-maximum sharpness: larger is closer to the plain union (sharper creases between lobes).
K = 6.0
CENTER = np.array([-1.5, -0.3, 1.0])


def rotation(rx_deg, ry_deg, rz_deg):
    """R = Rz Ry Rx (degrees)."""
    ax, ay, az = np.radians([rx_deg, ry_deg, rz_deg])
    rx = np.array([[1, 0, 0], [0, np.cos(ax), -np.sin(ax)], [0, np.sin(ax), np.cos(ax)]])
    ry = np.array([[np.cos(ay), 0, np.sin(ay)], [0, 1, 0], [-np.sin(ay), 0, np.cos(ay)]])
    rz = np.array([[np.cos(az), -np.sin(az), 0], [np.sin(az), np.cos(az), 0], [0, 0, 1]])
    return rz @ ry @ rx


# (centre, semi-axes, rotation in degrees about x, y, z): x to the patient's left (negative) and
# right (positive), y front to back, z foot to head.
LOBES = [
    # right lobe: the large, thick part
    (np.array([3.2, 0.0, 0.0]), np.array([5.6, 6.6, 5.6]), (0.0, 8.0, -10.0)),
    # left lobe: smaller, thinner, reaching to the left and slightly up and forward
    (np.array([-4.6, -1.0, 1.6]), np.array([6.2, 4.4, 2.3]), (0.0, -12.0, 14.0)),
    # caudate lobe: a small bulge at the back
    (np.array([0.6, 3.6, 0.4]), np.array([2.2, 2.0, 3.0]), (0.0, 0.0, 0.0)),
    # bridge between the lobes, so that the waist between them is smooth
    (np.array([-0.6, -0.2, 0.9]), np.array([4.0, 4.6, 3.4]), (0.0, -6.0, 5.0)),
]
# The lower side is flattened by the half-space n.x <= d (smoothly intersected).
FLAT_NORMAL = np.array([0.18, 0.0, -1.0]) / np.linalg.norm([0.18, 0.0, -1.0])
FLAT_OFFSET = 4.3


def organ_shape(seed):
    """The shape parameters (lobes, flat normal, flat offset, stretch) of seed `seed`; seed 0 is
    the reference organ above, unchanged."""
    if seed == 0:
        return LOBES, FLAT_NORMAL, FLAT_OFFSET, np.ones(3)
    rng = np.random.default_rng(seed)
    lobes = []
    for c, a, rot in LOBES:
        lobes.append((c + rng.normal(0.0, 0.4, 3), a * np.exp(rng.normal(0.0, 0.1, 3)),
                      tuple(np.array(rot) + rng.normal(0.0, 5.0, 3))))
    tilt = rotation(*rng.normal(0.0, 4.0, 3))
    normal = tilt @ FLAT_NORMAL
    offset = FLAT_OFFSET + rng.normal(0.0, 0.4)
    stretch = np.exp(rng.normal(0.0, 0.08, 3))
    return lobes, normal / np.linalg.norm(normal), offset, stretch


def field(x, shape=None):
    """F(x) > 0 inside, < 0 outside; x is (n, 3); `shape` from organ_shape (default: seed 0).
    The stretch acts about CENTER: F(x) = F_0(CENTER + (x - CENTER) / stretch)."""
    lobes, flat_normal, flat_offset, stretch = shape if shape is not None else organ_shape(0)
    if (stretch != 1.0).any():
        x = CENTER + (x - CENTER) / stretch
    terms = []
    for c, a, rot in lobes:
        q = ((x - c) @ rotation(*rot)) / a  # rows: R^T (x - c) / a
        terms.append(1.0 - np.sum(q * q, axis=1))
    terms = np.array(terms)
    m = terms.max(axis=0)
    union = m + np.log(np.exp(K * (terms - m)).sum(axis=0)) / K
    plane = (flat_offset - x @ flat_normal) / flat_offset  # 1 at the centre side, 0 on the plane
    # smooth minimum of the union and the half-space
    lo = np.minimum(union, plane)
    return lo - np.log(np.exp(-K * (union - lo)) + np.exp(-K * (plane - lo))) / K


def icosphere(level):
    t = (1.0 + np.sqrt(5.0)) / 2.0
    p = [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t], [0, -1, -t],
         [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]]
    f = [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
         [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9],
         [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]]
    pts = [np.array(q, float) / np.linalg.norm(q) for q in p]
    for _ in range(level):
        mid = {}

        def midpoint(a, b):
            key = (min(a, b), max(a, b))
            if key not in mid:
                m = pts[a] + pts[b]
                pts.append(m / np.linalg.norm(m))
                mid[key] = len(pts) - 1
            return mid[key]

        g = []
        for a, b, c in f:
            ab, bc, ca = midpoint(a, b), midpoint(b, c), midpoint(c, a)
            g += [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
        f = g
    return np.array(pts), np.array(f, dtype=np.int64)


def ray_radii(dirs, shape=None, r_max=30.0, n_coarse=600, n_bisect=60):
    """For each unit direction, the radius where F changes sign along C + r u; checks that there
    is exactly one sign change (the solid is star-shaped about C)."""
    r = np.linspace(0.0, r_max, n_coarse)
    vals = field((CENTER[None, None, :] + r[None, :, None] * dirs[:, None, :]).reshape(-1, 3), shape)
    vals = vals.reshape(len(dirs), n_coarse)
    inside = vals > 0
    if not inside[:, 0].all():
        raise SystemExit("error: the centre is not inside the solid")
    changes = np.count_nonzero(inside[:, 1:] != inside[:, :-1], axis=1)
    if (changes != 1).any():
        bad = int(np.argmax(changes != 1))
        raise SystemExit(f"error: ray {bad} crosses the surface {changes[bad]} times: not star-shaped")
    k = np.argmax(~inside, axis=1)  # first sample outside
    lo, hi = r[k - 1].copy(), r[k].copy()
    for _ in range(n_bisect):
        mid = 0.5 * (lo + hi)
        fin = field(CENTER[None, :] + mid[:, None] * dirs, shape) > 0
        lo = np.where(fin, mid, lo)
        hi = np.where(fin, hi, mid)
    return 0.5 * (lo + hi)


def half_extents(shape=None, level=3):
    """Half-extents of the solid about C, from a coarse radial sample."""
    dirs, _ = icosphere(level)
    x = CENTER + ray_radii(dirs, shape)[:, None] * dirs
    return np.maximum(np.abs(x - CENTER).max(axis=0), 1e-9)


def make_surface(level, seed=0):
    shape = organ_shape(seed)
    v, tri = icosphere(level)
    dirs = v * half_extents(shape)[None, :]
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    # Stretching by a positive diagonal keeps every spherical triangle positively oriented.
    det = np.einsum("ij,ij->i", dirs[tri[:, 0]], np.cross(dirs[tri[:, 1]], dirs[tri[:, 2]]))
    assert (det > 0).all()
    x = CENTER + ray_radii(dirs, shape)[:, None] * dirs
    return x, tri


def report(x, tri):
    a, b, c = x[tri[:, 0]], x[tri[:, 1]], x[tri[:, 2]]
    n = np.cross(b - a, c - a)
    area2 = np.linalg.norm(n, axis=1)
    volume = np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0
    if not volume > 0:
        raise SystemExit("error: triangles are not outward")
    edges = np.concatenate([np.linalg.norm(b - a, axis=1), np.linalg.norm(c - b, axis=1),
                            np.linalg.norm(a - c, axis=1)])

    def angle(p, q, r):
        u, w = q - p, r - p
        cosv = np.einsum("ij,ij->i", u, w) / (np.linalg.norm(u, axis=1) * np.linalg.norm(w, axis=1))
        return np.degrees(np.arccos(np.clip(cosv, -1, 1)))

    min_angle = np.minimum(np.minimum(angle(a, b, c), angle(b, c, a)), angle(c, a, b)).min()
    unit_n = n / area2[:, None]
    # dihedral (normal) angle across every edge
    edge_faces = {}
    for f, t in enumerate(tri):
        for k in range(3):
            key = (min(t[k], t[(k + 1) % 3]), max(t[k], t[(k + 1) % 3]))
            edge_faces.setdefault(key, []).append(f)
    if any(len(fs) != 2 for fs in edge_faces.values()):
        raise SystemExit("error: the surface is not closed")
    pairs = np.array(list(edge_faces.values()))
    turn = np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", unit_n[pairs[:, 0]], unit_n[pairs[:, 1]]), -1, 1)))
    ext = x.max(axis=0) - x.min(axis=0)
    print(f"{len(x)} points, {len(tri)} triangles; extent {ext[0]:.2f} x {ext[1]:.2f} x {ext[2]:.2f} "
          f"(ratios {ext[0] / ext[2]:.2f} : {ext[1] / ext[2]:.2f} : 1); volume {volume:.1f}")
    print(f"edges {edges.min():.3f}..{edges.max():.3f} (median {np.median(edges):.3f}); smallest "
          f"angle {min_angle:.1f} deg; normal turn across edges median {np.median(turn):.1f}, "
          f"max {turn.max():.1f} deg")
    return min_angle, turn.max()


def write_stl(path, x, tri, seed=0):
    a, b, c = x[tri[:, 0]], x[tri[:, 1]], x[tri[:, 2]]
    n = np.cross(b - a, c - a)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    header = b"hypershape synthetic liver-like stand-in (scripts/make_organ_surface.py)"
    if seed:
        header += b" seed %d" % seed
    tmp = path + ".tmp"
    with open(tmp, "wb") as f:
        f.write(header.ljust(80, b" "))
        f.write(struct.pack("<I", len(tri)))
        rec = np.zeros(len(tri), dtype=[("n", "<f4", 3), ("a", "<f4", 3), ("b", "<f4", 3),
                                         ("c", "<f4", 3), ("attr", "<u2")])
        rec["n"], rec["a"], rec["b"], rec["c"] = n, a, b, c
        f.write(rec.tobytes())
    os.replace(tmp, path)


def main():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--out", default=os.path.join(root, "configs", "surfaces", "organ.stl"))
    ap.add_argument("--level", type=int, default=None,
                    help="icosphere level (default: 4 for --out, 3 for --livers)")
    ap.add_argument("--seed", type=int, default=0,
                    help="0: the reference organ; other seeds vary it (default: %(default)s)")
    ap.add_argument("--livers", metavar="DIR",
                    help="write --count surfaces DIR/liver_000.stl, ... (seeds 1, 2, ...)")
    ap.add_argument("--count", type=int, default=5, help="surfaces for --livers (default: %(default)s)")
    args = ap.parse_args()
    if args.seed < 0 or args.count < 1:
        ap.error("--seed must be >= 0 and --count >= 1")
    if not args.livers:
        x, tri = make_surface(4 if args.level is None else args.level, args.seed)
        report(x, tri)
        os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
        write_stl(args.out, x, tri, args.seed)
        print(f"wrote {args.out}")
        return 0
    # level 3 (1280 triangles, 64 KB each) keeps the shipped stand-ins small.
    level = 3 if args.level is None else args.level
    os.makedirs(args.livers, exist_ok=True)
    seed = 0
    for k in range(args.count):
        while True:
            seed += 1
            x, tri = make_surface(level, seed)
            print(f"seed {seed}: ", end="")
            min_angle, max_turn = report(x, tri)
            if min_angle >= 12.0 and max_turn <= 65.0:
                break
            print(f"seed {seed} skipped: a triangle angle below 12 deg or a normal turn above 65 deg")
        path = os.path.join(args.livers, f"liver_{k:03d}.stl")
        write_stl(path, x, tri, seed)
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
