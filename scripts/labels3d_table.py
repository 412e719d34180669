#!/usr/bin/python3
"""Tables of the 3D label study (scripts/study_labels3d.sh; docs/ACCURACY.md, "3D labels").

    scripts/labels3d_table.py results/labels3d/ball.json results/labels3d/r3d-0.json \
        [--md docs/labels3d/table.md] [--json docs/labels3d/table.json]

Per scene: the reference's own error from its ladder (the local sizes at the clamp rim and p_N
halved twice: ref0.05, ref0.025 and the reference ref0.0125, all compared with the reference),
assuming the errors shrink geometrically by q per halving: e(s) = ||u_s - u_ref|| gives
rho = e(0.025) / e(0.05) = q / (1 + q), and the reference's error is q^2 e(0.05) / (1 - q^2);
max|u| is extrapolated the same way (Richardson with the observed order). Then every option:
DoFs, Newton iterations, seconds per load case (the fixed-alpha solve, plus the mesh and set-up
shared by `loads_per_shape` load cases, or all of it for a per-load-case mesh), rel L2 of u on
the label's vertices (nodal and lumped-volume weighted), the error of max|u|, error x seconds.
"""
import argparse
import json
import math
import sys
from pathlib import Path


def ladder(res, names=("ref0.05", "ref0.025")):
    by = {r["name"]: r for r in res["results"]}
    if not all(n in by and "error" in by[n] for n in names):
        return None
    e1, e2 = by[names[0]]["error"]["rel_l2_volume"], by[names[1]]["error"]["rel_l2_volume"]
    rho = e2 / e1
    out = {"e_0.05": e1, "e_0.025": e2, "rho": rho}
    if 0 < rho < 0.5:
        q = rho / (1 - rho)
        out.update(q=q, order=-math.log2(q), ref_rel_l2=q * q * e1 / (1 - q * q))
    m = [by[n]["max_u"] for n in names] + [by[res["reference"]]["max_u"]]
    d1, d2 = m[1] - m[0], m[2] - m[1]
    out["max_u"] = m
    if d1 != 0 and d2 / d1 > 0 and abs(d2 / d1) < 1:
        r = d2 / d1
        extrap = m[2] + d2 * r / (1 - r)
        out.update(max_u_extrapolated=extrap, ref_max_u_error=m[2] / extrap - 1, max_u_ratio=r)
    return out


def rows(res):
    out = []
    for r in res["results"]:
        if "dofs" not in r:  # an option whose mesh could not be made: its reason is in the JSON
            print(f"{res['scene']}: {r['name']} {r['reason']}", file=sys.stderr)
            continue
        e = r.get("error", {})
        l2 = e.get("rel_l2_volume")
        out.append({
            "name": r["name"], "dofs": r["dofs"], "vertices": r["vertices"], "newton": r["newton_iterations"],
            "per_load_mesh": r["per_load_case_mesh"], "label_on": r["label_on"],
            "seconds_per_load_case": r["seconds_per_load_case"],
            "seconds_solve": r["seconds_solve_alpha"], "seconds_mesh_setup": r["seconds_mesh"] + r["seconds_setup"],
            "rel_l2_volume": l2, "rel_l2_nodal": e.get("rel_l2_nodal"), "max_u_rel_error": e.get("max_u_rel_error"),
            "error_x_seconds": l2 * r["seconds_per_load_case"] if l2 is not None else None,
            "converged": r["converged"]})
    return out


def fmt(v, p="{:.2%}"):
    return "-" if v is None else p.format(v)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("results", nargs="+")
    ap.add_argument("--md", default="docs/labels3d/table.md")
    ap.add_argument("--json", default="docs/labels3d/table.json")
    a = ap.parse_args()
    tables, md = {}, []
    for path in a.results:
        res = json.loads(Path(path).read_text())
        lad = ladder(res)
        rs = rows(res)
        tables[res["scene"]] = {"alpha": res["alpha"], "reference": res["reference"], "ladder": lad, "rows": rs}
        md.append(f"### {res['scene']} (alpha {res['alpha']}, reference {res['reference']})\n")
        if lad:
            md.append(f"Reference ladder: e(0.05) = {lad['e_0.05']:.2%}, e(0.025) = {lad['e_0.025']:.2%} "
                      f"(rho {lad['rho']:.2f}); " +
                      (f"observed order {lad['order']:.2f}, estimated reference error {lad['ref_rel_l2']:.2%} rel L2"
                       if "ref_rel_l2" in lad else "no geometric convergence seen (rho >= 0.5): error not estimated") +
                      ("; max|u| " + ", ".join(f"{m:.4f}" for m in lad["max_u"]) +
                       (f", extrapolated {lad['max_u_extrapolated']:.4f} (reference {lad['ref_max_u_error']:+.2%})"
                        if "max_u_extrapolated" in lad else " (not monotone: not extrapolated)")) + "\n")
        md.append("| option | DoFs | Newton | mesh per load case | s per load case | rel L2 u (volume) | rel L2 u (nodal) | max\\|u\\| error | error x s |")
        md.append("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
        for r in rs:
            md.append(f"| {r['name']} | {r['dofs']} | {r['newton']} | {'yes, label on ' + r['label_on'] if r['per_load_mesh'] else 'no'} | "
                      f"{r['seconds_per_load_case']:.2f} | {fmt(r['rel_l2_volume'])} | {fmt(r['rel_l2_nodal'])} | "
                      f"{fmt(r['max_u_rel_error'], '{:+.2%}')} | {fmt(r['error_x_seconds'], '{:.4f}')} |")
        md.append("")
    Path(a.json).write_text(json.dumps(tables, indent=1) + "\n")
    Path(a.md).write_text("\n".join(md) + "\n")
    print("\n".join(md))


if __name__ == "__main__":
    main()
