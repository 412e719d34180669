#!/usr/bin/python3
"""The effectivity of the labels' error estimate (docs/ACCURACY.md, issue 19) from the JSON
lines of study_error_estimate (scripts/error_estimate_study.sh):

  error_estimate_report.py docs/error_estimate/*.jsonl [--plot docs/figures/error_estimate.png]
  error_estimate_report.py ESTIMATE_ONLY.jsonl --truths docs/error_estimate/*.jsonl

(--truths: the true errors of `study_error_estimate --estimate-only` runs, taken from the runs with
references of the same cases: case label, shape, load and target alike)

prints a markdown table per case family (label: scene or preset, degree, h) and over all:
effectivity index estimate / true of the relative L2 error of u (and |max|u|| and |alpha|
errors), its median and 10-90% spread, the share of cases within [0.5, 2], and the estimate's
cost next to the solve (seconds and CG iterations). --plot draws estimate vs true, log-log."""
import argparse
import json
import sys

import numpy as np

QUANTITIES = (("rel_l2", "relative L2 of u"), ("max_u", "max|u|"), ("alpha", "alpha"))


def lines(files):
    for f in files:
        for line in open(f):
            if line.strip():
                yield json.loads(line)


def case_key(r):
    return r["case"], r["shape"], r["load"], round(r["target"], 9)


def load(files, truths=()):
    known = {case_key(t): t for t in lines(truths) if "true_rel_l2" in t}
    rows = []
    for r in lines(files):
        if "true_rel_l2" not in r and case_key(r) in known:
            r.update({k: v for k, v in known[case_key(r)].items() if k.startswith("true_")})
        if r.get("converged") and r.get("estimate_ok") and "true_rel_l2" in r:
            rows.append(r)
    return rows


def effectivity(rows, q):
    est = np.array([abs(r[f"est_{q}"]) for r in rows])
    true = np.array([abs(r[f"true_{q}"]) for r in rows])
    ok = true > 0
    return est[ok] / true[ok]


def line(name, rows):
    cells = [name, str(len(rows))]
    for q, _ in QUANTITIES:
        e = effectivity(rows, q)
        if len(e) == 0:
            cells.append("-")
            continue
        within = 100.0 * np.mean((e >= 0.5) & (e <= 2.0))
        cells.append(f"{np.median(e):.2f} [{np.percentile(e, 10):.2f}, {np.percentile(e, 90):.2f}] {within:.0f}%")
    true = np.array([r["true_rel_l2"] for r in rows])
    share = np.array([r["estimate_seconds"] / max(r["solve_seconds"], 1e-12) for r in rows])
    its = np.array([r["estimate_krylov_iterations"] for r in rows])
    fact = np.array([r["solve_factorizations"] for r in rows])
    steps = np.array([r.get("estimate_tangent_assemblies", 2) - 1 for r in rows])
    cells += [f"{np.median(true):.2g}", f"{100 * np.median(share):.0f}% ({100 * np.max(share):.0f}%)",
              f"{np.median(its):.0f}", f"{np.median(fact):.0f} / 1", f"{np.mean(steps):.2f}"]
    return "| " + " | ".join(cells) + " |"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("files", nargs="+")
    ap.add_argument("--plot", help="PNG: estimate against true error, log-log")
    ap.add_argument("--truths", nargs="+", default=[], help="runs with references: the true errors of estimate-only runs")
    a = ap.parse_args()
    rows = load(a.files, a.truths)
    if not rows:
        print("no complete cases", file=sys.stderr)
        return 1
    families = {}
    for r in rows:
        families.setdefault(r["case"], []).append(r)
    print("| cases | n | effectivity rel. L2: median [p10, p90] within [0.5, 2] | max\\|u\\| | alpha "
          "| median true rel. L2 | estimate / solve time: median (max) | GMRES its | factorisations: solve / estimate "
          "| fine Newton steps (mean) |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for name in sorted(families):
        print(line(name, families[name]))
    for dim in (2, 3):
        sub = [r for r in rows if r["dim"] == dim]
        if sub and len(sub) != len(rows):
            print(line(f"**all {dim}D**", sub))
    print(line("**all**", rows))
    if a.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, axes = plt.subplots(1, 3, figsize=(15, 4.8))
        # One colour per family (the default cycle repeats after 10), 3D drawn as squares.
        colours = {name: plt.cm.tab20(k % 20) for k, name in enumerate(sorted(families))}
        for ax, (q, title) in zip(axes, QUANTITIES):
            lo, hi = np.inf, 0
            for name in sorted(families):
                fr = [r for r in families[name] if abs(r[f"true_{q}"]) > 0]
                t = np.array([abs(r[f"true_{q}"]) for r in fr])
                e = np.array([abs(r[f"est_{q}"]) for r in fr])
                keep = (t > 0) & (e > 0)
                if keep.any():
                    marker = "s" if fr[0].get("dim") == 3 else "o"
                    ax.loglog(t[keep], e[keep], marker, ms=4, alpha=0.75, color=colours[name], label=name)
                    lo, hi = min(lo, t[keep].min(), e[keep].min()), max(hi, t[keep].max(), e[keep].max())
            if hi > 0:
                x = np.array([lo / 2, hi * 2])
                ax.loglog(x, x, "k-", lw=1, label="estimate = true")
                ax.loglog(x, 2 * x, "k:", lw=1, label="x 2, x 1/2")
                ax.loglog(x, x / 2, "k:", lw=1)
            ax.set_xlabel(f"true error ({title})")
            ax.set_ylabel("estimate")
            ax.set_title(f"{title}: |estimate| vs |true|")
        axes[0].legend(fontsize=7)
        fig.tight_layout()
        fig.savefig(a.plot, dpi=110)
        print(f"\n(plot: {a.plot})", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
