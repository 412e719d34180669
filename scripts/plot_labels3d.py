#!/usr/bin/python3
"""The 3D label study as a picture: label error against unknowns for every option the study
measured (scripts/study_labels3d.sh; docs/ACCURACY.md, "3D labels"), one panel per scene, the
errors against the converged mean-dilatation reference refm0.0125 (its own error 0.2-0.3%), the
4% mark, the random3d preset of each date circled.

    scripts/plot_labels3d.py [--out docs/figures/labels3d_pareto.png] [JSON ...]

Default inputs: docs/labels3d/{r3d-0,ball}_mean*.json (an option measured in several runs is
plotted from the last file named, in name order by default; the errors are deterministic, the seconds are not, so the
x axis is the option's unknowns). The Pareto front (fewest unknowns for the error) is drawn.
"""
import argparse
import glob
import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

PRESETS = {"u0.3": "h 0.3, pointwise (to 2026-11-24)", "rim0.25m10": "h 0.25, rim 0.1 (2026-11-25)",
           "s0.22i0.3rim12m": "surface 0.22, interior 0.3, rim 0.125 (2026-11-26)"}


def options(files, scene):
    """name -> (dofs, rel L2) of the scene's options, references left out, last file wins."""
    out = {}
    for f in files:
        d = json.load(open(f))
        if d.get("scene") != scene or d.get("reference") != "refm0.0125":
            continue
        for r in d["results"]:
            if r.get("converged") and "error" in r and not r["name"].startswith("ref"):
                out[r["name"]] = (r["dofs"], 100 * r["error"]["rel_l2_volume"])
    return out


def front(points):
    best, out = float("inf"), []
    for name, (n, e) in sorted(points.items(), key=lambda kv: kv[1]):
        if e < best:
            best = e
            out.append((n, e))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("files", nargs="*")
    ap.add_argument("--out", default="docs/figures/labels3d_pareto.png")
    a = ap.parse_args()
    files = a.files or sorted(glob.glob("docs/labels3d/*_mean*.json"))
    if not files:
        raise SystemExit("plot_labels3d.py: no study JSON (run scripts/study_labels3d.sh, or name the files)")
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.8))
    for ax, scene in zip(axes, ("r3d-0", "ball")):
        pts = options(files, scene)
        if not pts:
            raise SystemExit(f"plot_labels3d.py: no {scene} results against refm0.0125 in {files}")
        for name, (n, e) in pts.items():
            ax.scatter(n / 1000, e, s=14, color="0.55", zorder=2)
            ax.annotate(name, (n / 1000, e), fontsize=6, color="0.35", xytext=(3, 2), textcoords="offset points")
        fx, fy = zip(*front(pts))
        ax.plot([x / 1000 for x in fx], fy, "-", color="tab:blue", lw=1, label="Pareto front", zorder=1)
        for (name, label), c in zip(PRESETS.items(), ("tab:gray", "tab:orange", "tab:green")):
            if name in pts:
                n, e = pts[name]
                ax.scatter(n / 1000, e, s=90, facecolors="none", edgecolors=c, lw=2, label=f"random3d: {label}", zorder=3)
        ax.axhline(4.0, color="tab:red", ls="--", lw=1, label="4% (a third of the paper's best model)")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("unknowns (thousands)")
        ax.set_ylabel("label error: rel. L2 of u at the same traction (%)")
        ax.set_title(f"{scene}: against refm0.0125 (mean dilatation)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
    fig.tight_layout()
    Path(a.out).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(a.out, dpi=130)
    print(f"wrote {a.out} from {len(files)} files")


if __name__ == "__main__":
    main()
