#!/usr/bin/python3
"""Table, JSON and strong-scaling projection of scripts/bench_groups.sh's runs.

Each run left in WORK: <solver>-np<n>-<k>.out (hypershape solve's summary line), .time (GNU
time: wall, user, sys seconds, max RSS KiB of mpiexec's children), .log (-log_view) and .h5 (u).

Projection (AMG solvers only; a sparse factorisation's fronts scale differently, see the README):
the solve is counted in MatMults (every level's, smoothers included: each exchanges ghost values
with the neighbours; a Krylov iteration adds a few all-reduces). t1: the 1-rank run's seconds
per MatMult (solve time / MatMult count: compute only). g2: the ghost values per rank and
MatMult of the 2-rank run (MatMult's average message length in -log_view, levels averaged).
A partition of a 3D body into p compact parts has an interface per part that scales like
(N/p)^(2/3): g(p) = g2 (2/p)^(2/3) k(p), k(p) = min(6, 1 + (p - 2)/2) (one cut face per half at
p = 2, up to neighbours on all sides). Seconds per MatMult at p ranks:
    t(p) = t1 / p + latency msgs(p) + 8 g(p) / bandwidth + 2 log2(p) latency / 4,
msgs(p) = min(26, p - 1), latency 2e-6 s, bandwidth 5e9 B/s (an InfiniBand-class cluster:
stated assumptions, not measurements). The AMG's iteration count is assumed independent of p
(GAMG aggregates per rank; the 1- and 2-rank counts are in the table).
"""
import argparse
import glob
import json
import math
import os
import re
import statistics
import sys


def parse_out(path):
    text = open(path).read()
    m = re.search(r"(\d+)D P(\d+): (\d+) vertices, (\d+) cells, (\d+) dofs \| (.*?) \| alpha ([\d.e+-]+), max\|u\| ([\d.e+-]+)",
                  text)
    if not m:
        raise SystemExit(f"{path}: no summary line:\n{text}")
    r = {"dim": int(m[1]), "degree": int(m[2]), "vertices": int(m[3]), "cells": int(m[4]), "dofs": int(m[5]),
         "converged": m[6] == "converged", "alpha": float(m[7]), "max_u": float(m[8])}
    m = re.search(r"(\d+) Newton iterations in (\d+) solves", text)
    r["newton_iterations"] = int(m[1]) if m else None
    for k, v in re.findall(r" (mesh|setup|solve|gather) ([\d.]+)s", text):
        r[f"seconds_{k}"] = float(v)
    return r


def parse_log(path):
    """Event counts/times and the run's message totals from -log_view."""
    ev, tot = {}, {}
    for line in open(path):
        f = line.split()
        if line.startswith("MPI Msg Count:"):
            tot["messages"] = float(f[-1])
        elif line.startswith("MPI Msg Len (bytes):"):
            tot["message_bytes"] = float(f[-1])
        elif line.startswith("MPI Reductions:"):
            tot["reductions"] = float(f[2])
        elif len(f) >= 10 and f[0] in ("HSFactor", "HSFactorSolve", "HSKrylov", "HSAMGSetup", "HSStability", "HSTangentAsm",
                                        "MatMult", "KSPSolve", "PCSetUp", "PCApply", "MatCholFctrNum", "MatSolve"):
            try:
                ev[f[0]] = {"count": int(f[1]), "seconds": float(f[3]), "messages": float(f[7]), "avg_bytes": float(f[8]),
                            "reductions": float(f[9])}
            except ValueError:
                pass
    return ev, tot


def parse_time(path):
    wall, user, sys_, rss = open(path).read().split()[-4:]
    return {"wall": float(wall), "user": float(user), "sys": float(sys_), "max_rss_kib": int(rss)}


def project(t1, ghost2, levels=4):
    """Seconds per MatMult-equivalent at p ranks: the 1-rank run's compute split p ways plus the
    modelled exchange (the 2-rank run's ghost count scaled to p parts)."""
    lat, bw = 2e-6, 5e9
    out = {}
    for p in (2, 8, 16, 32, 64):
        k = min(6.0, 1 + (p - 2) / 2)
        g = ghost2 * (2 / p) ** (2 / 3) * k
        msgs = min(26, p - 1)
        t = t1 / p + lat * msgs + g * 8 / bw + 2 * math.log2(p) * lat / levels
        out[p] = {"seconds_per_matmult": t, "ghost_values_per_rank": g, "speedup_vs_1": t1 / t}
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("work")
    ap.add_argument("out")
    ap.add_argument("--h", type=float)
    ap.add_argument("--target", type=float)
    ap.add_argument("--repeats", type=int)
    ap.add_argument("--solvers", nargs="+")
    ap.add_argument("--ranks", nargs="+", type=int)
    a = ap.parse_args()
    runs = []
    for s in a.solvers:
        for n in a.ranks:
            for k in range(a.repeats):
                tag = f"{s}-np{n}-{k}"
                if not os.path.exists(f"{a.work}/{tag}.log"):  # a run cut short: the others stand
                    continue
                r = {"solver": s, "ranks": n, "repeat": k, **parse_out(f"{a.work}/{tag}.out")}
                r["time"] = parse_time(f"{a.work}/{tag}.time")
                r["events"], r["totals"] = parse_log(f"{a.work}/{tag}.log")
                runs.append(r)
    # The same u on every configuration (to the solver tolerance): max nodal difference against
    # the first run, read from the solution files.
    try:
        import h5py
        import numpy as np

        def u_of(tag):
            with h5py.File(f"{a.work}/{tag}.h5", "r") as f:
                for name in ("displacement", "u", "fields/displacement"):
                    if name in f:
                        return np.asarray(f[name])
            return None
        ref = u_of(f"{a.solvers[0]}-np{a.ranks[0]}-0")
        for r in runs:
            u = u_of(f"{r['solver']}-np{r['ranks']}-{r['repeat']}")
            if ref is not None and u is not None and u.shape == ref.shape:
                r["max_abs_du_vs_first"] = float(np.max(np.abs(u - ref)))
    except ImportError:
        pass
    med = {}
    for s in a.solvers:
        for n in a.ranks:
            sel = [r for r in runs if r["solver"] == s and r["ranks"] == n]
            if not sel:
                raise SystemExit(f"no finished run of {s} on {n} ranks")
            med[(s, n)] = {"solve_s": statistics.median(r["seconds_solve"] for r in sel),
                           "wall_s": statistics.median(r["time"]["wall"] for r in sel),
                           "solve_runs": [r["seconds_solve"] for r in sel], "first": sel[0]}
    print(f"\nGroup scaling: unit ball P2 h {a.h}, {runs[0]['dofs']} unknowns, target max|u| {a.target}, "
          f"medians of up to {a.repeats} (1- and 2-rank runs interleaved; the machine was shared)")
    print(f"{'solver':8} {'ranks':>5} {'solve s':>9} {'runs':>24} {'speed-up':>8} {'Newton':>6} {'factor.':>7} "
          f"{'MatMult':>7} {'AMG set':>7} {'msgs':>8} {'MiB sent':>8} {'ghosts/rank':>11} {'max|du|':>9}")
    table = []
    for s in a.solvers:
        base = med[(s, a.ranks[0])]["solve_s"]
        for n in a.ranks:
            m = med[(s, n)]
            f = m["first"]
            ev = f["events"]
            mm = ev.get("MatMult", {})
            ghosts = mm.get("avg_bytes", 0) / 8 if n > 1 else 0
            kry = ev.get("KSPSolve", {}).get("count", 0)
            row = {"solver": s, "ranks": n, "median_solve_seconds": m["solve_s"], "solve_seconds_runs": m["solve_runs"],
                   "median_wall_seconds": m["wall_s"], "speedup": base / m["solve_s"],
                   "newton_iterations": f["newton_iterations"], "factorisations": ev.get("HSFactor", {}).get("count", 0),
                   "krylov_solves": ev.get("HSKrylov", {}).get("count", 0), "amg_setups": ev.get("HSAMGSetup", {}).get("count", 0),
                   "matmults": mm.get("count", 0), "messages": f["totals"].get("messages", 0),
                   "message_bytes": f["totals"].get("message_bytes", 0), "ghost_values_per_rank": ghosts,
                   "max_abs_du_vs_first": max((r.get("max_abs_du_vs_first", float("nan")) for r in runs
                                              if r["solver"] == s and r["ranks"] == n), default=float("nan"))}
            table.append(row)
            runs_txt = " ".join(f"{x:.1f}" for x in m["solve_runs"])
            print(f"{s:8} {n:5d} {m['solve_s']:9.2f} {runs_txt:>24} {row['speedup']:8.2f} {row['newton_iterations']!s:>6} "
                  f"{row['factorisations']:7d} {row['matmults']:7d} {row['amg_setups']:7d} {row['messages']:8.0f} "
                  f"{row['message_bytes'] / 2**20:8.1f} {ghosts:11.0f} {row['max_abs_du_vs_first']:9.2e}")
    # Strong-scaling projection of the AMG solvers from the 2-rank run's MatMult communication.
    proj = {}
    for s in a.solvers:
        if s == "direct" or 2 not in a.ranks:
            continue
        f = med[(s, 2)]["first"]
        mm = f["events"].get("MatMult", {})
        t1 = med[(s, a.ranks[0])]["solve_s"] / max(med[(s, a.ranks[0])]["first"]["events"].get("MatMult", {}).get("count", 1), 1)
        pr = project(t1, mm.get("avg_bytes", 0) / 8)
        proj[s] = pr
        print(f"\nProjection ({s}; per MatMult-equivalent of work (all levels, smoothers included), model in scripts/bench_groups_table.py): "
              + ", ".join(f"p={p}: {v['seconds_per_matmult'] * 1e3:.2f} ms ({v['speedup_vs_1']:.1f}x, "
                          f"{v['ghost_values_per_rank']:.0f} ghosts)" for p, v in pr.items()))
    json.dump({"h": a.h, "target": a.target, "repeats": a.repeats, "machine": "2 cores, shared with other jobs",
               "table": table, "projection": {s: {str(p): v for p, v in pr.items()} for s, pr in proj.items()},
               "runs": runs}, open(a.out, "w"), indent=1)
    print(f"\n[bench_groups] JSON: {a.out}")


if __name__ == "__main__":
    main()
