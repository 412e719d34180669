#!/usr/bin/env bash
# Two builds of hypershape side by side on the same dataset slice, alternately on 1 rank:
# seconds per load case, numeric factorisations, Krylov and Newton iterations per load case
# (factorisations from the run report's solver.numeric_factorizations where a build writes it,
# else PETSc's log: MatCholFctrNum plus HSFactorBlocked; Krylov: KSPGMRESOrthog), the converged share, and how
# far the two datasets' displacements are apart on the load cases both converged,
# and the run reports' phases side by side (shape, mesh, solve, alpha search, representations, io):
# seconds per 100 load cases, medians over the runs.
#   scripts/bench_versions.sh OTHER_HYPERSHAPE [SHAPES] [LOADS] [REPEATS]
#   SHAPES_H=0.12 MESH='{degree: 2}' scripts/bench_versions.sh /tmp/old/hypershape 8 25 1
#   PRESET=random3d MESH='{degree: 2, h: 0.3}' scripts/bench_versions.sh /tmp/old/hypershape 4 25 1
# Environment: PRESET (default random2d), SHAPES_H (shapes.h: the 2D mesh size), MESH (a mesh:
# override, e.g. '{degree: 2}'; mesh.h is the 3D solve mesh size),
# SOLVER (a solver: override for this build only, e.g. '{factor_reuse: false}'), THIS_HYPERSHAPE
# (this build's binary, default build/hypershape: a copy keeps a long run apart from rebuilds).
# Where a preset changed between the versions, the same problem needs other words in each:
# OTHER_PRESET (the other build's preset name, default PRESET), THIS_MESH (this build's mesh:
# override, default MESH) and THIS_YAML (more top-level lines for this build only), e.g. the
# random3d preset of 256a82b (P2, mesh.h 0.3, pointwise dilatation) against today's build:
#   PRESET=random3d MESH='{degree: 2, h: 0.3}' THIS_MESH='{degree: 2, h: 0.3, surface_h: 0.3, rim: 0}' \
#   THIS_YAML='material: {dilatation: pointwise}' scripts/bench_versions.sh /tmp/base256/build/hypershape 5 20 2
# JSON: results/bench_versions.json. Build the other version with e.g.
#   git worktree add /tmp/old HEAD~1 && (cd /tmp/old && scripts/setup.sh)
set -euo pipefail
cd "$(dirname "$0")/.."
other=${1:?usage: scripts/bench_versions.sh OTHER_HYPERSHAPE [SHAPES] [LOADS] [REPEATS]}
shapes=${2:-20} loads=${3:-50} repeats=${4:-1}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
slice() {  # $1: file, $2: preset, $3: mesh block, $4: solver block, $5: more lines
  {
    echo "preset: $2"
    echo "name: bench_versions"
    echo "shapes: {count: $shapes${SHAPES_H:+, h: $SHAPES_H}}"
    echo "loads: {count: $loads}"
    echo "output: {shard_size: 4}"
    if [ -n "$3" ]; then echo "mesh: $3"; fi
    if [ -n "$4" ]; then echo "solver: $4"; fi
    if [ -n "$5" ]; then echo "$5"; fi
  } > "$1"
}
slice "$work/this.yaml" "${PRESET:-random2d}" "${THIS_MESH:-${MESH:-}}" "${SOLVER:-}" "${THIS_YAML:-}"
slice "$work/other.yaml" "${OTHER_PRESET:-${PRESET:-random2d}}" "${MESH:-}" "" ""
for ((k = 0; k < repeats; ++k)); do
  "${THIS_HYPERSHAPE:-build/hypershape}" -q generate "$work/this.yaml" --progress 0 -o "$work/this-$k" -- -log_view ":$work/this-$k.log"
  "$other" -q generate "$work/other.yaml" --progress 0 -o "$work/other-$k" -- -log_view ":$work/other-$k.log"
  echo "run $((k + 1))/$repeats done" >&2
done
mkdir -p results
/usr/bin/python3 - "$work" "$repeats" "$other" <<'PY'
import glob, json, re, statistics, sys
import h5py, numpy as np
work, repeats, other = sys.argv[1], int(sys.argv[2]), sys.argv[3]

def count(log, event):
    for line in open(log):
        if line.startswith(event + " "):
            return int(line.split()[1])
    return 0

def run(tag, k):
    rep = json.load(open(f"{work}/{tag}-{k}/reports/task-000-of-001.json"))
    lc = rep["load_cases"]["converged"] + rep["load_cases"]["failed"]
    log = f"{work}/{tag}-{k}.log"
    return {"seconds_per_load_case": rep["seconds"]["wall"] / lc, "load_cases": lc,
            "converged": rep["load_cases"]["converged"],
            # The run report's own count where it has one (since 2026-11-26; it also counts MUMPS's
            # single-precision factorisations, which PETSc's log does not see), else PETSc's log.
            "numeric_factorizations_per_load_case": rep["solver"].get(
                "numeric_factorizations", count(log, "MatCholFctrNum") + count(log, "HSFactorBlocked")) / lc,
            "krylov_iterations_per_load_case": count(log, "KSPGMRESOrthog") / lc,
            "newton_iterations_per_load_case": rep["solver"]["newton_iterations"] / lc,
            "factorization_seconds_per_load_case": rep["seconds"]["factorization_PCSetUp_summed_over_ranks"] / lc,
            # Where the time went: the run report's phases (shape, mesh, solve, io, ...), per load case.
            "phase_seconds_per_load_case": {k: v / lc for k, v in
                                            rep["seconds"].get("phases_summed_over_groups", {}).items()}}

runs = {t: [run(t, k) for k in range(repeats)] for t in ("this", "other")}
med = {t: {key: statistics.median(r[key] for r in runs[t]) for key in runs[t][0]
           if key != "phase_seconds_per_load_case"} for t in runs}
for t in runs:  # a phase's median over the runs (a phase one build does not have counts as 0)
    names = sorted({p for r in runs[t] for p in r["phase_seconds_per_load_case"]})
    med[t]["phase_seconds_per_load_case"] = {
        p: statistics.median(r["phase_seconds_per_load_case"].get(p, 0.0) for r in runs[t]) for p in names}

# The datasets, load case by load case (first repeat): displacement of the cases both converged.
diffs, only = [], {"this": 0, "other": 0}
for fa in sorted(glob.glob(f"{work}/this-0/shards/*.h5")):
    fb = fa.replace("/this-0/", "/other-0/")
    with h5py.File(fa) as a, h5py.File(fb) as b:
        for s in a["shapes"]:
            if "loads" not in a["shapes"][s] or "loads" not in b["shapes"][s]:
                continue
            la, lb = a["shapes"][s]["loads"], b["shapes"][s]["loads"]
            sa, sb = la["status"][:], lb["status"][:]
            only["this"] += int(((sa == 1) & (sb != 1)).sum())
            only["other"] += int(((sb == 1) & (sa != 1)).sum())
            for i in np.where((sa == 1) & (sb == 1))[0]:
                ua, ub = la["displacement"][i], lb["displacement"][i]
                diffs.append(float(np.abs(ua - ub).max() / max(np.abs(ub).max(), 1e-300)))
diffs = np.array(diffs)
out = {"other": other, "repeats": repeats, "runs": runs, "medians": med,
       "u_rel_diff": {"both_converged": int(diffs.size), "median": float(np.median(diffs)) if diffs.size else None,
                      "max": float(diffs.max()) if diffs.size else None,
                      "above_1e-6": int((diffs > 1e-6).sum())},
       "converged_only_in": only}
json.dump(out, open("results/bench_versions.json", "w"), indent=1)
print(f"{runs['this'][0]['load_cases']} load cases per run, {repeats} run(s) each, alternated; medians:")
print("| version | s / load case | numeric factorisations / case | Krylov its / case | Newton its / case | factorisation s / case | converged |")
print("|---|---|---|---|---|---|---|")
for t, name in (("this", "this build"), ("other", other)):
    m = med[t]
    print(f"| {name} | {m['seconds_per_load_case']:.4f} | {m['numeric_factorizations_per_load_case']:.2f} "
          f"| {m['krylov_iterations_per_load_case']:.1f} | {m['newton_iterations_per_load_case']:.1f} "
          f"| {m['factorization_seconds_per_load_case']:.4f} | {m['converged']}/{m['load_cases']} |")
ratio = med["other"]["seconds_per_load_case"] / med["this"]["seconds_per_load_case"]
print(f"speed-up (other / this, seconds per load case): {ratio:.2f}x")
ph = {t: med[t]["phase_seconds_per_load_case"] for t in med}
print("\n| phase (medians) | this: s / 100 load cases | other | other / this |\n|---|---|---|---|")
for p in sorted(set(ph["this"]) | set(ph["other"])):
    a, b = 100 * ph["this"].get(p, 0.0), 100 * ph["other"].get(p, 0.0)
    if a > 0.005 or b > 0.005:
        print(f"| {p} | {a:.2f} | {b:.2f} | {b / a:.2f}x |" if a > 0 else f"| {p} | {a:.2f} | {b:.2f} | - |")
u = out["u_rel_diff"]
print(f"displacement, load cases converged in both ({u['both_converged']}): max|u_this - u_other| / max|u_other| "
      f"median {u['median']:.1e}, max {u['max']:.1e}; {u['above_1e-6']} above 1e-6 (another equilibrium of the same "
      f"max|u|); converged only in this build: {only['this']}, only in the other: {only['other']}")
print("JSON: results/bench_versions.json")
PY
