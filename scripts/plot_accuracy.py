#!/usr/bin/python3
"""Pareto plots and tables of the accuracy/time study (drivers/study_accuracy.cpp, issue 6).

    scripts/plot_accuracy.py results/study_accuracy.json [--fig-dir docs/figures]
                             [--table results/study_accuracy.md] [--suffix ""]

Per dimension, every setting is one point: x = wall time per load case (mean over the scenes
and load cases of the median over repeats), y = relative L2 error of u at the reference's nodes
(mean over the same), log-log; two panels: the error at the same target max|u| (the usual
convergence check), and the error as a training pair, against the reference solved at the
setting's own alpha ("same load": what a model trained on the pair (traction, u) learns). The Pareto front (no other setting is both faster and more
accurate) is drawn as a line, the dataset default as a star, the reference's own estimated
error (Richardson) as a dashed line: errors near or below it are not resolved by the study.
A setting that failed on any load case of the dimension is left out of the front and listed.

Writes docs/figures/accuracy_pareto_{2d,3d}.png and a markdown file with one table per
dimension and the findings (the default's error, the front, what 10x smaller error costs, the
comparison with the seed paper's Table 2, and the cheapest setting within each dataset's error
budget). Needs numpy and matplotlib (Debian packages).
"""
import argparse
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

# The seed paper's Table 2 (tab:in-dist, in-distribution results): mean
# relative L2 error of the best and the worst model per dataset.
TABLE2 = {
    2: {"OneRandom2D": (0.0057, 0.0191), "EasyRandom2D": (0.0293, 0.0965), "Random2D": (0.1180, 0.2921)},
    3: {"OneLiver": (0.0378, 0.0474), "Liver": (0.1677, 0.2179), "Random3D": (0.1271, 0.1766)},
}

GROUP_STYLE = {
    "mesh": ("o", "tab:blue"),
    "tolerance": ("s", "tab:gray"),
    "quadrature": ("v", "tab:purple"),
    "newton_rtol": ("^", "tab:orange"),
    "target_rtol": ("<", "tab:red"),
    "control": (">", "tab:brown"),
    "path_rtol": ("D", "tab:pink"),
    "linear_solver": ("P", "tab:green"),
    "linear_model": ("X", "tab:olive"),
}


TIME_KEY = "seconds"  # or "cpu_seconds" (--time cpu)


def aggregate(study, dim):
    """Per setting name: mean metrics over every (scene, load case) of the dimension. A setting
    that ran on only some of the scenes (a knob of one scene's own baseline, e.g. easy-0's P2)
    is marked incomplete: its means are over other scenes than the rest's, so the fronts and
    findings leave it out, and the table names its scenes."""
    rows = {}
    refs = []
    kinds = {}
    for sc in study["scenes"]:
        if sc.get("dim") != dim or "error" in sc:
            continue
        kinds[sc["name"]] = sc.get("kind", "")
        ref = sc["reference"]
        refs.append({"scene": sc["name"], "h": ref["h"], "dofs": ref["dofs"],
                     "l2": ref.get("richardson_l2_mean"), "h1": ref.get("richardson_h1_mean"),
                     "alpha": ref.get("richardson_alpha_mean"),
                     "order": [r["l2"]["order_observed"] for r in ref["richardson"]],
                     "order_assumed": any(r["l2"]["order_assumed"] for r in ref["richardson"]),
                     "seconds": sum(l.get("seconds_total", 0) for l in ref["ladder"][:1])})
        for r in sc["results"]:
            s = r["setting"]
            row = rows.setdefault(s["name"], {"setting": s, "l2": [], "h1": [], "alpha": [], "solver": [], "same": [],
                                             "sec": [], "sec_am": [], "dofs": [], "rss": [], "failed": 0,
                                             "n": 0, "scenes": {}, "errors": [], "covers": set()})
            row["covers"].add(sc["name"])
            if "error" in r:
                row["errors"].append(f"{sc['name']}: {r['error']}")
                row["failed"] += len(sc["load_cases"])
                row["n"] += len(sc["load_cases"])
                continue
            row["dofs"].append(r["dofs"])
            if r.get("peak_rss_delta_mib") is not None:
                row["rss"].append(r["peak_rss_delta_mib"])
            per_scene = []
            amort = (r["seconds_mesh"] + r["seconds_setup"]) / sc["loads_per_shape_in_preset"]
            for lo in r["loads"]:
                row["n"] += 1
                if not lo["converged"]:
                    row["failed"] += 1
                    row["errors"].append(f"{sc['name']}: {lo['reason']}")
                    continue
                row["l2"].append(lo["rel_l2"])
                row["h1"].append(lo["rel_h1"])
                row["alpha"].append(lo["alpha_err"])
                if lo.get("same_load_rel_l2") is not None:
                    row["same"].append(lo["same_load_rel_l2"])
                if lo.get("solver_l2") is not None:
                    row["solver"].append(lo["solver_l2"])
                t = lo.get(TIME_KEY, lo["seconds"])
                row["sec"].append(t)
                row["sec_am"].append(t + amort)
                per_scene.append((t, lo["rel_l2"], lo.get("same_load_rel_l2")))
            row["scenes"][sc["name"]] = per_scene
    out = []
    for name, row in rows.items():
        m = lambda v: float(np.mean(v)) if v else float("nan")  # noqa: E731
        out.append({"name": name, "setting": row["setting"], "group": row["setting"]["group"],
                    "default": row["setting"]["is_default"], "ok": row["failed"] == 0 and row["n"] > 0,
                    "failed": row["failed"], "n": row["n"], "errors": row["errors"],
                    "l2": m(row["l2"]), "h1": m(row["h1"]), "alpha": m(row["alpha"]), "solver": m(row["solver"]),
                    # the training-pair error, only where every load case has it
                    "same": m(row["same"]) if len(row["same"]) == len(row["l2"]) else float("nan"),
                    "same_worst_scene": worst_scene(row["scenes"], kinds),
                    "sec": m(row["sec"]), "sec_am": m(row["sec_am"]), "dofs": m(row["dofs"]),
                    "rss": max(row["rss"]) if row["rss"] else float("nan"), "scenes": row["scenes"],
                    "covers": sorted(row["covers"]), "complete": row["covers"] == set(kinds)})
    return out, refs


def worst_scene(per_scene, kinds):
    """The largest per-scene mean same-load error over the random shapes (every dataset is made
    of random shapes; the disk's and ball's patch-end singularities leave their references' own
    alpha error near 1%), or over all scenes when there is no random one."""
    names = [n for n in per_scene if kinds.get(n, "").startswith("random")] or list(per_scene)
    vals = [float(np.mean([p[2] for p in per_scene[n]])) for n in names
            if per_scene[n] and all(p[2] is not None for p in per_scene[n])]
    return max(vals) if len(vals) == len(names) and vals else float("nan")


def scene_metric(study, scene, setting):
    """(mean rel L2, mean alpha error, mean same-load rel L2 or None) of one setting on one scene;
    None if absent or failed."""
    for sc in study["scenes"]:
        if sc["name"] != scene or "error" in sc:
            continue
        for r in sc["results"]:
            if r["setting"]["name"] == setting and "error" not in r:
                ls = [lo for lo in r["loads"] if lo["converged"]]
                if len(ls) != len(r["loads"]):
                    return None
                same = [lo.get("same_load_rel_l2") for lo in ls]
                return (float(np.mean([lo["rel_l2"] for lo in ls])), float(np.mean([lo["alpha_err"] for lo in ls])),
                        float(np.mean(same)) if all(v is not None for v in same) else None)
    return None


def pareto(rows, key_t="sec", key_e="l2"):
    """Names on the front: no other (converged) setting has both smaller time and smaller error."""
    ok = [r for r in rows if r["ok"] and r["group"] != "diagnostic" and math.isfinite(r[key_t])
          and math.isfinite(r[key_e])]
    ok.sort(key=lambda r: (r[key_t], r[key_e]))
    front, best = [], float("inf")
    for r in ok:
        if r[key_e] < best * (1 - 1e-6):  # ties (the same answer, by round-off) are no gain
            front.append(r)
            best = r[key_e]
    return front


def time_at_error(front, e, key_e="l2"):
    """Time on the front (log-log linear interpolation) at error e; None outside its range."""
    pts = sorted(((r[key_e], r["sec"]) for r in front), key=lambda p: p[0])
    if not pts or e < pts[0][0] or e > pts[-1][0]:
        return None
    for (e0, t0), (e1, t1) in zip(pts, pts[1:]):
        if e0 <= e <= e1:
            if e1 == e0:
                return t0
            w = (math.log(e) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(t0) + w * (math.log(t1) - math.log(t0)))
    return pts[0][1]


def fmt_e(v):
    return "-" if v is None or not math.isfinite(v) else f"{v:.2e}"


def fmt_t(v):
    if v is None or not math.isfinite(v):
        return "-"
    return f"{v * 1e3:.0f} ms" if v < 1 else f"{v:.2f} s"


def panel(ax, rows, refs, front, key_e, point_index):
    """One error-vs-time panel: every setting (per-scene points faint), the front, the default."""
    for r in rows:
        if not r["ok"]:
            continue
        marker, color = GROUP_STYLE.get(r["group"], ("o", "k"))
        for pts in r["scenes"].values():
            pts = [p for p in pts if p[point_index] is not None]
            if pts:
                ax.scatter([p[0] for p in pts], [p[point_index] for p in pts], s=8, marker=marker, color=color,
                           alpha=0.18, linewidths=0)
    seen = set()
    for r in rows:
        if not r["ok"] or not math.isfinite(r[key_e]):
            continue
        marker, color = GROUP_STYLE.get(r["group"], ("o", "k"))
        label = r["group"] if r["group"] not in seen else None
        seen.add(r["group"])
        ax.scatter(r["sec"], r[key_e], s=46, marker=marker, color=color, edgecolors="k", linewidths=0.5,
                   label=label, zorder=3)
    ax.step([r["sec"] for r in front], [r[key_e] for r in front], where="post", color="k", lw=1.2, zorder=2,
            label="Pareto front")
    default = next((r for r in rows if r["default"] and r["ok"]), None)
    for r in front:
        if default is not None and r is not default and math.isfinite(default[key_e]) \
                and abs(r[key_e] / default[key_e] - 1) < 0.01 and abs(math.log(r["sec"] / default["sec"])) < 0.5:
            continue  # the default's own answer, reached by a knob that changes nothing: the star says it
        ax.annotate(r["name"], (r["sec"], r[key_e]), textcoords="offset points", xytext=(5, 4), fontsize=7)
    if default is not None and math.isfinite(default[key_e]):
        ax.scatter(default["sec"], default[key_e], s=260, marker="*", facecolors="none", edgecolors="red",
                   linewidths=1.5, zorder=4, label="dataset default")
        ax.annotate(default["name"], (default["sec"], default[key_e]), textcoords="offset points", xytext=(5, -11),
                    fontsize=7, color="red")
    est = [x["l2"] for x in refs if x["l2"] is not None]
    if est and key_e == "l2":
        ax.axhline(float(np.mean(est)), color="gray", ls="--", lw=1, label="reference's own error (Richardson)")
    est_a = [x["alpha"] for x in refs if x["alpha"] is not None]
    if est_a and key_e == "same":
        ax.axhline(float(np.mean(est_a)), color="gray", ls="--", lw=1,
                   label="reference's own alpha error (Richardson)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(f"{'CPU' if TIME_KEY == 'cpu_seconds' else 'wall'} time per load case [s] "
                  "(median of repeats, mean over scenes and load cases)", fontsize=8)
    ax.grid(True, which="both", alpha=0.3)


def plot(rows, refs, front, front_same, dim, path, machine):
    rows = [r for r in rows if r["group"] != "diagnostic"]
    has_same = any(math.isfinite(r["same"]) for r in rows)
    fig, axes = plt.subplots(1, 2 if has_same else 1, figsize=(15.0 if has_same else 8.5, 6.0), squeeze=False)
    ax = axes[0][0]
    panel(ax, rows, refs, front, "l2", 1)
    ax.set_ylabel("relative L2 error of u vs the reference, at the same target max|u|")
    ax.set_title(f"{dim}D, at the same target ({', '.join(x['scene'] for x in refs)}); "
                 f"{machine.get('nproc', '?')} cores, {machine.get('cpu_model', '?')[:40]}", fontsize=9)
    ax.legend(fontsize=7, loc="best")
    if has_same:
        ax = axes[0][1]
        panel(ax, rows, refs, front_same, "same", 2)
        lo, hi = ax.get_ylim()
        x0 = ax.get_xlim()[0]
        for name, (best, _) in TABLE2.get(dim, {}).items():  # the budgets within the plotted range
            if lo <= best <= hi * 3:
                ax.axhline(best, color="tab:red", ls=":", lw=0.9)
                ax.annotate(f"{name} best model", (x0, best), textcoords="offset points", xytext=(3, 2),
                            fontsize=6.5, color="tab:red")
        ax.set_ylabel("relative L2 error of u vs the reference at the same load (the training pair)")
        ax.set_title(f"{dim}D, as a training pair: the same traction alpha g phi; dotted: Table 2's best models",
                     fontsize=9)
    fig.tight_layout()
    os.makedirs(os.path.dirname(path) or ".", exist_ok=True)
    fig.savefig(path, dpi=130)
    plt.close(fig)


def report(study, dims, fig_dir, suffix, table_dir):
    lines = [f"# Accuracy/time study ({study.get('mode')})", ""]
    m = study.get("machine", {})
    lines.append(f"Machine: {m.get('nproc')} cores, {m.get('cpu_model')}, {m.get('petsc_version')}; "
                 f"load average at start {study.get('load_average_start')}, end {study.get('load_average_end')}; "
                 f"total {study.get('seconds_total', 0):.0f} s; repeats {study['parameters']['repeats']}.")
    lines.append("")
    findings = {}
    for dim in dims:
        listed, refs = aggregate(study, dim)
        if not listed:
            continue
        rows = [r for r in listed if r["complete"]]  # compared over the same scenes
        front = pareto(rows)
        front_names = {r["name"] for r in front}
        front_same = pareto(rows, key_e="same")
        front_same_names = {r["name"] for r in front_same}
        path = os.path.join(fig_dir, f"accuracy_pareto_{dim}d{suffix}.png")
        plot(rows, refs, front, front_same, dim, path, m)
        lines.append(f"## {dim}D")
        lines.append("")
        lines.append(f"![{dim}D Pareto plot]({os.path.relpath(path, table_dir)})")
        lines.append("")
        lines.append("References (P2, rtol 1e-10, target_rtol 1e-6) and their own estimated error:")
        lines.append("")
        lines.append("| scene | h_ref | DoFs | rel L2 (Richardson) | rel H1 | alpha | observed order (L2, per load case) |")
        lines.append("|---|---|---|---|---|---|---|")
        for x in refs:
            orders = ", ".join("-" if o is None else f"{o:.2f}" for o in x["order"])
            lines.append(f"| {x['scene']} | {x['h']} | {x['dofs']} | {fmt_e(x['l2'])} | {fmt_e(x['h1'])} | "
                         f"{fmt_e(x['alpha'])} | {orders}{' (assumed 1)' if x['order_assumed'] else ''} |")
        lines.append("")
        lines.append("| setting | group | DoFs | time/load | amortised | rel L2 | rel H1 | alpha err | same-load L2 | "
                     "solver err | peak RSS +MiB | front | front (same load) |")
        lines.append("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
        for r in sorted(listed, key=lambda r: (not r["ok"], r["sec"] if math.isfinite(r["sec"]) else 1e99)):
            name = r["name"] + (" **(default)**" if r["default"] and r["complete"] else "")
            if not r["complete"]:
                name += f" [{', '.join(r['covers'])} only: not on the fronts]"
            if not r["ok"]:
                name += f" (failed {r['failed']}/{r['n']})"
            lines.append(f"| {name} | {r['group']} | {r['dofs']:.0f} | {fmt_t(r['sec'])} | {fmt_t(r['sec_am'])} | "
                         f"{fmt_e(r['l2'])} | {fmt_e(r['h1'])} | {fmt_e(r['alpha'])} | {fmt_e(r['same'])} | "
                         f"{fmt_e(r['solver'])} | {r['rss']:.0f} | {'yes' if r['name'] in front_names else ''} | "
                         f"{'yes' if r['name'] in front_same_names else ''} |")
        lines.append("")
        # Per scene: rel L2 (and alpha error) of the mesh and linear-model settings.
        scenes = [x["scene"] for x in refs]
        lines.append("Per scene, relative L2 error at the same target / alpha error / relative L2 error at the same "
                     "load (mean over the load cases):")
        lines.append("")
        lines.append("| setting | " + " | ".join(scenes) + " |")
        lines.append("|---|" + "---|" * len(scenes))
        lines.append("| reference's own (Richardson) | " + " | ".join(
            f"{fmt_e(x['l2'])} / {fmt_e(x['alpha'])} / -" for x in refs) + " |")
        for r in sorted(listed, key=lambda r: (r["group"] != "mesh", r["setting"]["degree"], -r["setting"]["h"])):
            if r["group"] not in ("mesh", "linear_model"):
                continue
            cells = []
            for name in scenes:
                vals = scene_metric(study, name, r["name"])
                cells.append("-" if vals is None else f"{fmt_e(vals[0])} / {fmt_e(vals[1])} / {fmt_e(vals[2])}")
            lines.append(f"| {r['name']}{' (default)' if r['default'] else ''} | " + " | ".join(cells) + " |")
        lines.append("")
        # Findings.
        f = {"front": [r["name"] for r in front], "front_same_load": [r["name"] for r in front_same]}
        default = next((r for r in rows if r["default"]), None)
        lines.append(f"Pareto front (fastest first): {', '.join(f['front'])}.")
        f["front_alpha"] = [r["name"] for r in pareto(rows, key_e="alpha")]
        lines.append(f"Pareto front in the alpha error: {', '.join(f['front_alpha'])}.")
        if front_same:
            lines.append(f"Pareto front in the same-load (training-pair) error: {', '.join(f['front_same_load'])}.")
        # Budgets: a dataset's samples, as training pairs, should be at least as accurate as the
        # best model reported on it (Table 2), on every random shape (the worst one's mean), and
        # stricter, three times as accurate (then the data's error moves a model's measured error
        # by at most ~5%, errors adding in quadrature).
        budget_rows = []
        for ds, (best, _) in TABLE2.get(dim, {}).items():
            for label, budget in ((f"{ds} (best model {best:.4f})", best), (f"{ds} / 3", best / 3)):
                ok = [r for r in rows if r["ok"] and r["group"] in ("mesh", "linear_model")
                      and math.isfinite(r["same_worst_scene"]) and r["same_worst_scene"] <= budget]
                pick = min(ok, key=lambda r: r["sec"]) if ok else None
                budget_rows.append({"dataset": ds, "budget": budget, "strict": budget != best,
                                    "cheapest": pick["name"] if pick else None,
                                    "same_worst_scene": pick["same_worst_scene"] if pick else None,
                                    "sec": pick["sec"] if pick else None})
                lines.append(f"- budget {label}: same-load error <= {budget:.4f} on every random shape: cheapest "
                             + (f"{pick['name']} (worst scene {fmt_e(pick['same_worst_scene'])}, {fmt_t(pick['sec'])} "
                                f"per load case)" if pick else "none of the settings here"))
        f["budgets"] = budget_rows
        if default and default["ok"]:
            f["default"] = {"name": default["name"], "l2": default["l2"], "h1": default["h1"],
                            "alpha": default["alpha"], "same": default["same"],
                            "same_worst_scene": default["same_worst_scene"], "sec": default["sec"]}
            on = default["name"] in front_names
            # The same discrete answer reached by a knob that changes nothing but the timing.
            twin = [r for r in front if r["group"] in ("tolerance", "newton_rtol", "target_rtol", "path_rtol")
                    and abs(r["l2"] / default["l2"] - 1) < 1e-3]
            where = "on the front" if on else (
                f"on the front within the timing noise (the same answer, reached by {twin[0]['name']} in "
                f"{fmt_t(twin[0]['sec'])}, is on it)" if twin else "not on the front")
            f["default"]["on_front"] = on or bool(twin)
            lines.append(f"Default ({default['name']}): rel L2 {fmt_e(default['l2'])}, rel H1 {fmt_e(default['h1'])}, "
                         f"alpha {fmt_e(default['alpha'])}, same-load rel L2 {fmt_e(default['same'])} (worst scene "
                         f"{fmt_e(default['same_worst_scene'])}), {fmt_t(default['sec'])} per load case; {where}.")
            t10s = time_at_error(front_same, default["same"] / 10, "same") if math.isfinite(default["same"]) else None
            f["time_front_same_at_tenth"] = t10s
            if t10s is not None:
                lines.append(f"10x smaller same-load error ({fmt_e(default['same'] / 10)}) on its front: {fmt_t(t10s)} "
                             f"per load case, {t10s / default['sec']:.1f}x the default's time.")
            t_same = time_at_error(front, default["l2"])
            t10 = time_at_error(front, default["l2"] / 10)
            f["time_front_at_default_error"] = t_same
            f["time_front_at_tenth"] = t10
            ref_err = [x["l2"] for x in refs if x["l2"] is not None]
            ref_mean = float(np.mean(ref_err)) if ref_err else float("nan")
            if math.isfinite(ref_mean) and default["l2"] / 10 < 2 * ref_mean:
                lines.append(f"Caution: 10x smaller error ({fmt_e(default['l2'] / 10)}) is within twice the reference's own "
                             f"estimated error ({fmt_e(ref_mean)}): the figure below is at the study's resolution limit.")
            if t10 is not None:
                lines.append(f"10x smaller error ({fmt_e(default['l2'] / 10)}) on the front: {fmt_t(t10)} per load "
                             f"case, {t10 / default['sec']:.1f}x the default's time"
                             + (f" ({t10 / t_same:.1f}x the front's time at the default's error)" if t_same else "")
                             + ".")
            else:
                best = min((r for r in front), key=lambda r: r["l2"])
                lines.append(f"10x smaller error ({fmt_e(default['l2'] / 10)}) is not reached by any setting here; "
                             f"the most accurate on the front is {best['name']} ({fmt_e(best['l2'])}, "
                             f"{fmt_t(best['sec'])}).")
            ref_err = [x["l2"] for x in refs if x["l2"] is not None]
            if ref_err:
                lines.append(f"Reference's own estimated error: {fmt_e(float(np.mean(ref_err)))} (mean over scenes).")
            for ds, (best, worst) in TABLE2.get(dim, {}).items():
                lines.append(f"- vs Table 2, {ds}: best model {best:.4f}, worst {worst:.4f}: the default's "
                             f"discretisation error is {default['l2'] / best * 100:.0f}% of the best model's error "
                             f"and {default['l2'] / worst * 100:.0f}% of the worst's.")
        if default and default["ok"]:
            # Settings that solve the default's discrete problem with the default's solver to the
            # same answer (tolerance knobs that do not change the path): their time spread is noise.
            same = [r for r in rows if r["ok"] and r["group"] in ("mesh", "tolerance", "newton_rtol", "target_rtol",
                                                                   "path_rtol")
                    and abs(r["l2"] - default["l2"]) <= 1e-3 * default["l2"]]
            if len(same) > 1:
                ts = sorted(r["sec"] for r in same)
                lines.append(f"- {len(same)} settings give the default's error to 3 digits with the default's linear "
                             f"solver ({', '.join(r['name'] for r in same)}); their times spread over {fmt_t(ts[0])} .. "
                             f"{fmt_t(ts[-1])}: time differences of that size are noise here, not cost.")
        failed = [r for r in listed if not r["ok"]]
        for r in failed:
            lines.append(f"- failed: {r['name']}: {r['failed']}/{r['n']} load cases; "
                         f"{'; '.join(sorted(set(r['errors']))[:3])}")
        lines.append("")
        findings[dim] = f
    return "\n".join(lines) + "\n", findings


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("json", nargs="?", default="results/study_accuracy.json")
    ap.add_argument("--fig-dir", default="docs/figures")
    ap.add_argument("--table", default=None, help="markdown output (default: the JSON path with .md)")
    ap.add_argument("--suffix", default="", help="appended to the figure names (e.g. _tiny)")
    ap.add_argument("--time", choices=["wall", "cpu"], default="wall",
                    help="time axis: wall time (default) or process CPU time of the load case")
    args = ap.parse_args()
    global TIME_KEY
    TIME_KEY = "cpu_seconds" if args.time == "cpu" else "seconds"
    with open(args.json) as fh:
        study = json.load(fh)
    dims = sorted({sc.get("dim") for sc in study["scenes"] if sc.get("dim")})
    table = args.table or os.path.splitext(args.json)[0] + ".md"
    text, findings = report(study, dims, args.fig_dir, args.suffix, os.path.dirname(os.path.abspath(table)))
    with open(table, "w") as fh:
        fh.write(text)
    with open(os.path.splitext(table)[0] + "_findings.json", "w") as fh:
        json.dump(findings, fh, indent=1)
    sys.stdout.write(text)


if __name__ == "__main__":
    main()
