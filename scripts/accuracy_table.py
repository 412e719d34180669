#!/usr/bin/env python3
"""What each accuracy level costs (issue 19, docs/ACCURACY.md "Datasets asked for by accuracy"):
one row per generated dataset directory, from its run report (reports/*.json: load cases, Newton
iterations, factorisations, the accuracy block) and its shards (the stored estimates, the level
each label and each shape's mesh were kept at); CPU seconds from a /usr/bin/time log when given.

  accuracy_table.py DIR... [--times times.log] [--json rows.json] [--plot figure.png]
  accuracy_table.py --from-json rows.json [--plot figure.png]     (the table and figure again)
  ... --before earlier.json        (the figure also draws an earlier study's cost per bound, dashed)

times.log lines: "<name> cpu_user U cpu_sys S wall W ..." where <name> is DIR's basename less
"out_" (scripts/study_accuracy_levels.sh writes it). The figure: per run the share of its load
cases whose estimate is at most x (the bounds marked), and the CPU seconds per load case of each
bound against the run without one. A directory that is not a generated dataset with estimates,
or a JSON file that is not this script's, stops it with exit code 1 and a message naming it."""
import argparse
import glob
import json
import os
import sys

import numpy as np


class InputError(Exception):
    pass


def cpu_seconds(path):
    out = {}
    if path:
        try:
            lines = open(path).read().splitlines()
        except OSError as e:
            raise InputError(f"{path}: {e.strerror}")
        for line in lines:
            w = line.split()
            if len(w) >= 5 and w[1] == "cpu_user":
                out[w[0]] = float(w[2]) + float(w[4])  # the last run of a name counts
    return out


def dataset(d, cpu):
    """One run's row (a dict), with the converged load cases' estimates."""
    import h5py

    reports = sorted(glob.glob(f"{d}/reports/*.json"))
    shards = sorted(glob.glob(f"{d}/shards/*.h5"))
    if not reports or not shards:
        raise InputError(f"{d}: not a generated dataset (no reports/*.json or shards/*.h5)")
    rep = json.load(open(reports[0]))
    s, lc = rep["solver"], rep["load_cases"]
    est, levels, labels, dofs = [], [], [], []
    for f in shards:
        with h5py.File(f) as h:
            for g in h["shapes"].values():
                if "loads" not in g:
                    continue  # a shape that failed
                if "error_estimate_rel_l2" not in g["loads"]:
                    raise InputError(f"{f}: shape {g.name} has no loads/error_estimate_rel_l2 (generate with "
                                     "representations: {error_estimate: true} or accuracy:)")
                levels.append(int(g.attrs.get("accuracy_level", 0)))
                dofs.append(g["nodes"].shape[0] * g["nodes"].shape[1])
                st = g["loads/status"][...]
                if "accuracy_level" in g["loads"]:
                    labels += [int(k) for k in g["loads/accuracy_level"][...][st == 1]]
                est += [float(e) for e in g["loads/error_estimate_rel_l2"][...][st == 1]]
    acc = rep.get("accuracy", {})
    name = os.path.basename(os.path.normpath(d)).removeprefix("out2_").removeprefix("out_")
    n_ok = lc["converged"]
    return {
        "name": name,
        "bound": acc.get("rel_l2_bound"),
        "converged": n_ok,
        "load_cases": lc["converged"] + lc["failed"],
        "share_meeting": acc.get("share_meeting"),
        "shapes_per_level": {str(k): levels.count(k) for k in sorted(set(levels))},
        "labels_per_level": {str(k): labels.count(k) for k in sorted(set(labels))},
        "mean_unknowns": float(np.mean(dofs)) if dofs else 0.0,
        "newton_per_load_case": s["newton_iterations"] / max(1, n_ok),
        "factorizations_per_load_case": s["numeric_factorizations"] / max(1, n_ok),
        "discarded_load_cases": acc.get("discarded_load_cases", 0),
        "load_cases_fell_back": acc.get("load_cases_fell_back", 0),
        "cpu_seconds": cpu.get(name),
        "estimates": est,
    }


def table(rows):
    lines = ["| run | bound | converged | estimate <= bound | labels per level | shapes per level | mean unknowns | estimate median / p90 / "
             "max | Newton its per load case | factorisations per load case | discarded load cases | CPU s | CPU s per "
             "load case | CPU per load case against the first run |",
             "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    base = per_case(rows[0]) if rows else None
    for r in rows:
        e = np.array(r["estimates"])
        est = f"{np.median(e):.3g} / {np.percentile(e, 90):.3g} / {e.max():.3g}" if len(e) else "-"
        meets = f"{100 * r['share_meeting']:.1f}%" if r["share_meeting"] is not None else "-"
        levels = lambda key: ", ".join(f"{k}: {n}" for k, n in r.get(key, {}).items()) if r["bound"] else "-"
        lv = levels("shapes_per_level")
        c, pc = r["cpu_seconds"], per_case(r)
        lines.append(
            f"| {r['name']} | {r['bound'] if r['bound'] else '-'} | {r['converged']}/{r['load_cases']} | {meets} | "
            f"{levels('labels_per_level') or '-'} | {lv} | "
            f"{r['mean_unknowns']:.0f} | {est} | {r['newton_per_load_case']:.1f} | "
            f"{r['factorizations_per_load_case']:.1f} | {discarded(r)} | {f'{c:.0f}' if c else '-'} | "
            f"{f'{pc:.2f}' if pc else '-'} | {f'{pc / base:.1f}x' if pc and base else '-'} |")
    return "\n".join(lines)


def discarded(r):
    """Labels not kept, and how many re-solves fell back to a level a jump had skipped."""
    n = r.get("load_cases_fell_back", 0)
    return f"{r['discarded_load_cases']}" + (f" ({n} re-solve{'s' * (n != 1)} at a skipped level)" if n else "")


def per_case(r):
    return r["cpu_seconds"] / max(1, r["converged"]) if r["cpu_seconds"] else None


def canonical(r):
    return r["name"] == f"rel_l2_{r['bound']:g}"


def label(r):
    if not r["bound"]:
        return "as configured"
    return f"bound {r['bound']:g}" + ("" if canonical(r) else f" ({r['name']})")


def read_rows(path):
    try:
        return json.load(open(path))["runs"]
    except (OSError, ValueError, KeyError, TypeError) as e:
        raise InputError(f"{path}: not a table this script wrote ({e})")


def cost_curve(bx, rows, fmt, name, **kw):
    """CPU per load case against the rows' first run, per canonical bound, its share annotated."""
    base = per_case(rows[0])
    main = [r for r in rows if r["bound"] and per_case(r) and canonical(r)]
    if not base or not main:
        return
    bx.plot([r["bound"] for r in main], [per_case(r) / base for r in main], fmt, label=name, **kw)
    for r in main:
        bx.annotate(f"{100 * r['share_meeting']:.1f}%", (r["bound"], per_case(r) / base),
                    textcoords="offset points", xytext=(4, 4), fontsize=8, **kw)


def plot(rows, path, before=None, before_name="before"):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.8))
    bounds = sorted({r["bound"] for r in rows if r["bound"]})
    for r in rows:
        e = np.sort(np.array([x for x in r["estimates"] if x > 0]))
        if not len(e):
            continue
        ax.step(e, np.arange(1, len(e) + 1) / r["converged"], where="post", label=label(r))
    for b in bounds:
        ax.axvline(b, color="0.6", ls=":", lw=1)
    ax.axhline(0.99, color="0.8", lw=0.8)
    ax.set(xscale="log", xlabel="estimated relative L2 error of u", ylabel="share of converged load cases <= x",
           title="the labels' estimates", ylim=(0, 1.01))
    ax.legend(fontsize=8, loc="upper left")
    base = per_case(rows[0]) if rows else None
    xs = [r for r in rows if r["bound"] and per_case(r)]
    if base and xs:
        first = np.array(rows[0]["estimates"])
        cost_curve(bx, rows, "o-", "asked for by accuracy (share meeting the bound)")
        if before:
            cost_curve(bx, before, "o--", before_name, color="0.55")
        for r in xs:
            if not canonical(r):
                bx.plot([r["bound"]], [per_case(r) / base], "x", ms=8, label=label(r))
                bx.annotate(f"{100 * r['share_meeting']:.1f}%", (r["bound"], per_case(r) / base),
                            textcoords="offset points", xytext=(4, 4), fontsize=8)
        if not rows[0]["bound"] and len(first):
            bb = sorted({r["bound"] for r in xs})
            bx.plot(bb, [1.0] * len(bb), "s", color="0.5", label=f"'{rows[0]['name']}' as configured")
            for b in bb:
                share = np.mean((first >= 0) & (first <= b)) * len(first) / rows[0]["converged"]
                bx.annotate(f"{100 * share:.0f}%", (b, 1.0), textcoords="offset points", xytext=(4, 4), fontsize=8)
        bx.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2, frameon=False)
        bx.margins(x=0.12, y=0.15)
        bx.set(xscale="log", yscale="log", xlabel="bound on the relative L2 error (accuracy: {rel_l2: B})",
               ylabel=f"CPU per load case / '{rows[0]['name']}'", title="what each bound costs")
        bx.invert_xaxis()
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("dirs", nargs="*")
    ap.add_argument("--times")
    ap.add_argument("--json", help="write the rows (with every estimate) here")
    ap.add_argument("--from-json", help="read the rows from a file --json wrote instead of datasets")
    ap.add_argument("--plot", help="write the figure here (PNG)")
    ap.add_argument("--before", help="an earlier study's rows (a file --json wrote), drawn dashed in the figure")
    ap.add_argument("--before-name", default="before", help="its legend entry")
    a = ap.parse_args()
    try:
        before = read_rows(a.before) if a.before else None
        if a.from_json:
            rows = read_rows(a.from_json)
        elif a.dirs:
            cpu = cpu_seconds(a.times)
            rows = [dataset(d, cpu) for d in a.dirs]
        else:
            raise InputError("give dataset directories or --from-json FILE")
    except InputError as e:
        print(f"accuracy_table.py: {e}", file=sys.stderr)
        return 1
    print(table(rows))
    try:
        if a.json:
            with open(a.json, "w") as f:
                json.dump({"runs": rows}, f, indent=1)
        if a.plot:
            plot(rows, a.plot, before, a.before_name)
    except OSError as e:
        print(f"accuracy_table.py: cannot write {e.filename}: {e.strerror}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
