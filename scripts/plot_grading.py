#!/usr/bin/python3
"""What grading the 2D meshes towards the Dirichlet patch ends buys and costs, per preset family
(docs/ACCURACY.md, "The random2d preset graded towards the patch ends"; issue 15), from the JSON
lines of `scripts/error_estimate_study.sh random2d_rim | easy_random2d_rim | one_random2d_rim`:

  plot_grading.py docs/error_estimate/rim/*.jsonl [--out docs/figures/grading_2d.png]

Each file is one setting of one family: its case label is FAMILY-P2-hH[-gradedG], G the patch
ends' edge length over h (0: as drawn, uniform there); a label without "-graded" is the preset
as it is, whose G is its mesh.rim / shapes.h (configs/presets/FAMILY.yaml). Per family only the
load cases with a true error at every setting are compared (shape and load alike), so each
setting is measured on the same cases. Prints a markdown table (true relative L2 error of u at
the same target: median, p10, p90, max; alpha's median; unknowns; Newton iterations per load
case) and draws the true error against the unknowns and against the Newton iterations, the
costs that do not depend on the host's load (the study's seconds do: it ran beside other jobs)."""
import argparse
import functools
import json
import os
import re
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
LABEL = re.compile(r"^(?P<family>[a-z0-9_]+)-P(?P<degree>\d)-h(?P<h>[0-9.]+)(?:-graded(?P<g>[0-9.]+))?$")


@functools.lru_cache(maxsize=None)
def preset_grading(family):
    """The preset's own patch-end size over h (mesh.rim / shapes.h), 0 where it has no rim."""
    import yaml  # python3-yaml, only where a file holds the preset as it is

    path = os.path.join(HERE, "..", "configs", "presets", f"{family}.yaml")
    try:
        cfg = yaml.safe_load(open(path))
        rim = (cfg.get("mesh") or {}).get("rim", 0.0)
        return float(rim) / float(cfg["shapes"]["h"])
    except (OSError, KeyError, TypeError, ValueError, yaml.YAMLError) as e:
        raise SystemExit(f"{path}: no preset '{family}' with shapes.h to read its grading from ({e})")


def load(files):
    """{family: {grading: {(shape, load): row}}} of the converged load cases with a true error."""
    out = {}
    for f in files:
        try:
            lines = open(f).read().splitlines()
        except OSError as e:
            raise SystemExit(f"{f}: cannot read ({e.strerror})")
        for n, line in enumerate(lines, 1):
            if not line.strip():
                continue
            try:
                r = json.loads(line)
                case, shape, load_id = r["case"], r["shape"], r["load"]
            except (ValueError, KeyError, TypeError) as e:
                raise SystemExit(f"{f}:{n}: not a study line with case, shape and load ({e})")
            m = LABEL.match(case)
            if not m:
                raise SystemExit(f"{f}: case label {case!r} is not FAMILY-P<degree>-h<h>[-graded<G>]")
            g = float(m["g"]) if m["g"] is not None else preset_grading(m["family"])
            if r.get("converged") and r.get("true_rel_l2") is not None:
                out.setdefault(m["family"], {}).setdefault(g, {})[(shape, load_id)] = r
    return out


def summarise(settings):
    """Per grading (as drawn first, then ever finer ends), the statistics over the cases every
    setting has (main refuses a family without one)."""
    common = sorted(set.intersection(*(set(cases) for cases in settings.values())))
    rows = []
    for g in sorted(settings, key=lambda g: (g != 0, -g)):
        cases = [settings[g][k] for k in common]
        err = np.array([c["true_rel_l2"] for c in cases])
        rows.append({
            "grading": g,
            "n": len(cases),
            "median": float(np.median(err)),
            "p10": float(np.percentile(err, 10)),
            "p90": float(np.percentile(err, 90)),
            "max": float(err.max()),
            "alpha": float(np.median([abs(c["true_alpha"]) for c in cases])),
            "dofs": float(np.median([c["n_dofs"] for c in cases])),
            "newton": float(np.mean([c["newton_iterations"] for c in cases])),
        })
    return rows


def setting_name(g):
    return "as drawn" if g == 0 else f"h/{1 / g:.3g}"


def table(data):
    out = ["| family | patch ends | load cases | true rel. L2 of u: median [p10, p90], max | alpha: median | "
           "unknowns (median) | Newton its per load case |", "|---|---|---|---|---|---|---|"]
    for family in sorted(data):
        for s in summarise(data[family]):
            out.append(f"| {family} | {setting_name(s['grading'])} | {s['n']} | {100 * s['median']:.2f}% "
                       f"[{100 * s['p10']:.2f}, {100 * s['p90']:.2f}], {100 * s['max']:.2f}% | {100 * s['alpha']:.2f}% | "
                       f"{s['dofs']:.0f} | {s['newton']:.1f} |")
    return "\n".join(out)


def plot(data, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker

    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), sharey=True)
    for family, colour in zip(sorted(data), ("C0", "C1", "C2", "C3")):
        rows = summarise(data[family])
        y = np.array([100 * s["median"] for s in rows])
        err = np.array([[100 * (s["median"] - s["p10"]) for s in rows], [100 * (s["p90"] - s["median"]) for s in rows]])
        for ax, key in zip(axes, ("dofs", "newton")):
            x = [s[key] for s in rows]
            ax.errorbar(x, y, yerr=err, color=colour, marker="o", capsize=3, label=f"{family} ({rows[0]['n']} load cases)")
            preset = preset_grading(family)
            for s, xi, yi in zip(rows, x, y):
                name = setting_name(s["grading"]) + (" (preset)" if abs(s["grading"] - preset) < 1e-9 else "")
                ax.annotate(name, (xi, yi), textcoords="offset points", xytext=(5, 4), fontsize=8, color=colour)
    axes[0].set_xlabel("unknowns per shape (median)")
    axes[1].set_xlabel("Newton iterations per load case (mean)")
    axes[0].set_ylabel("true relative L2 error of u, % (median, p10-p90)")
    for ax in axes:
        ax.set_yscale("log")
        ax.set_yticks([0.2, 0.3, 0.5, 1, 2, 3, 5])
        ax.yaxis.set_major_formatter(matplotlib.ticker.FormatStrFormatter("%g"))
        ax.yaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.suptitle("2D presets at P2: the mesh at the Dirichlet patch ends (as drawn, graded) against the PDE's solution")
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("files", nargs="+")
    ap.add_argument("--out", help="PNG to write (none: the table only)")
    a = ap.parse_args(argv)
    data = load(a.files)
    if not data:
        print("no converged load case with a true error in " + ", ".join(a.files), file=sys.stderr)
        return 1
    for family, settings in data.items():
        if len(settings) < 2:
            print(f"{family}: one setting only ({setting_name(next(iter(settings)))}): nothing to compare", file=sys.stderr)
            return 1
        if not set.intersection(*(set(c) for c in settings.values())):
            print(f"{family}: no load case has a true error at every setting", file=sys.stderr)
            return 1
    print(table(data))
    if a.out:
        plot(data, a.out)
        print(f"wrote {a.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
