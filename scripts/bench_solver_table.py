#!/usr/bin/env python3
"""Turn bench_solver JSON files into Markdown tables (for the README).

    scripts/bench_solver_table.py bench_2d.json bench_3d.json > tables.md

Cases from several files are concatenated in the order given; each file's machine note is
printed above the tables. Only the standard library is used.
"""
import argparse
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_table import fmt_time, fmt_ratio, fmt_int, table  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("files", nargs="+", help="JSON files written by bench_solver --json")
    args = ap.parse_args()

    cases, notes = [], []
    for path in args.files:
        with open(path) as f:
            data = json.load(f)
        m = data["machine"]
        s = data["settings"]
        notes.append(
            f"- `{path}`: {m['hostname']}, {m['nproc']} cores, {m['mpi_ranks']} rank(s), "
            f"{m['petsc_version'].strip()}, BLAS {m.get('libblas_so_3')}, "
            f"OPENBLAS_NUM_THREADS={m.get('OPENBLAS_NUM_THREADS')}, {s['repeats']} repeats "
            f"(median), PETSc args {' '.join(s.get('petsc_args', [])) or 'none'}, {m['date_utc']}"
        )
        cases += data["cases"]

    print("\n".join(notes))
    print()
    rows1, rows2, remarks = [], [], []
    for c in cases:
        tag = [c["dim"], f"P{c['degree']}", c["h"]]
        if c.get("error"):
            rows1.append(tag + [f"error: {c['error']}"] + [""] * 10)
            continue
        t, v, d = c["median_seconds"], c["values"], c["derived"]
        rows1.append(tag + [
            fmt_int(v.get("vertices")), fmt_int(v.get("free_dofs")),
            fmt_time(t.get("mesh")), fmt_time(t.get("setup")),
            f"{fmt_int(v.get('full_newton'))} ({fmt_int(v.get('full_increments'))}/"
            f"{fmt_int(v.get('full_failed_increments'))})",
            f"{v['alpha']:.4g}" if v.get("alpha") is not None else "-",
            fmt_time(t.get("full_solve")), fmt_ratio(d.get("full_solve_overhead")),
            f"{fmt_time(t.get('target_solve'))} ({fmt_int(v.get('target_solves'))}/"
            f"{fmt_int(v.get('target_newton'))})",
            f"{fmt_time(t.get('second_load'))} ({fmt_int(v.get('second_solves'))}/"
            f"{fmt_int(v.get('second_newton'))})",
        ])
        rows2.append(tag + [
            fmt_time(t.get("residual")), fmt_time(t.get("jacobian")),
            f"{fmt_time(t.get('residual_pointwise'))} ({fmt_ratio(d.get('residual_pointwise_speedup'))})",
            f"{fmt_time(t.get('jacobian_pointwise'))} ({fmt_ratio(d.get('jacobian_pointwise_speedup'))})",
            fmt_time(t.get("factor_first")), fmt_time(t.get("factor_repeat")),
            fmt_time(t.get("triangular_solve")),
            fmt_time(t["global_to_local"] + t["insert_bc"]) if "insert_bc" in t else "-",
        ])
        for n in c.get("notes", []):
            remarks.append(f"- {c['dim']}D P{c['degree']} h={c['h']}: {n}")

    print(table(["dim", "P", "h", "vertices", "DoFs", "mesh", "set-up",
                 "Newton its (incr/failed)", "alpha", "full solve", "overhead",
                 "alpha search (solves/its)", "2nd load case (solves/its)"], rows1))
    print()
    print(table(["dim", "P", "h", "residual", "Jacobian", "residual, PETSc pointwise (ratio)",
                 "Jacobian, PETSc pointwise (ratio)", "1st factorisation", "numeric factorisation",
                 "triangular solve", "to_local"], rows2))
    if remarks:
        print()
        print("\n".join(remarks))
    return 0


if __name__ == "__main__":
    sys.exit(main())
