#!/usr/bin/env bash
# Benchmark of the data factory: a slice of a preset (PRESET, default random2d; default 20 shapes
# x 50 load cases at the preset's discretisation and grids) generated on 1 and on 2 ranks,
# alternately, REPEATS times (default 3). Prints the median load cases per second of each, the
# per-phase split and peak memory per rank (of the median run), the 2-rank efficiency (ratio of
# the medians) and the projected time of the full preset (its shapes.count x loads.count, e.g.
# Random2D 1000 x 50, Random3D 1000 x 20); writes every run's figures as JSON.
#   scripts/bench_generate.sh [SHAPES] [LOADS] [REPEATS]    (JSON: results/bench_generate.json)
#   PRESET=random3d scripts/bench_generate.sh 10 20 1       (a Random3D slice of 200 load cases)
#   SEED=90210 ...                                          (another seed than the preset's)
#   SHAPES_H=0.12 MESH='{degree: 2}' ...                    (another discretisation: shapes.h, mesh:)
#   PRESET=random2d_p1 ...                                  (Random2D at P1 h 0.04, the preset until 2026-11-28)
# Two projections of the full preset: from the slice's rate (its wall time; a small slice ends
# with one rank idle while the other finishes the last shard), and from its work (phase seconds
# summed over ranks, spread evenly over the ranks, plus one shard of the full run's size run
# alone at the end: a bound on the full run's tail, where shards are handed out one at a time).
set -euo pipefail
cd "$(dirname "$0")/.."
shapes=${1:-20} loads=${2:-50} repeats=${3:-3}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cat > "$work/slice.yaml" <<YAML
preset: ${PRESET:-random2d}
name: bench_${PRESET:-random2d}${SEED:+
seed: $SEED}
shapes: {count: $shapes${SHAPES_H:+, h: $SHAPES_H}}
loads: {count: $loads}
output: {shard_size: 2}
YAML
if [ -n "${MESH:-}" ]; then echo "mesh: $MESH" >> "$work/slice.yaml"; fi
for ((k = 0; k < repeats; ++k)); do
  build/hypershape -q generate "$work/slice.yaml" --progress 0 -o "$work/np1-$k"
  mpiexec -n 2 build/hypershape -q generate "$work/slice.yaml" --progress 0 -o "$work/np2-$k"
  echo "run $((k + 1))/$repeats done" >&2
done
mkdir -p results
/usr/bin/python3 - "$work" "$shapes" "$loads" "$repeats" "configs/presets/${PRESET:-random2d}.yaml" <<'PY'
import json, statistics, sys
import yaml
work, shapes, loads, repeats = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4])
preset = yaml.safe_load(open(sys.argv[5]))
name = preset["name"]
full = preset["shapes"].get("count", 1) * preset["loads"]["count"]  # load cases of the full preset
runs = {n: [json.load(open(f"{work}/np{n}-{k}/reports/task-000-of-001.json")) for k in range(repeats)] for n in (1, 2)}
rates = {n: [x["load_cases"]["per_second"] for x in runs[n]] for n in (1, 2)}
rate = {n: statistics.median(rates[n]) for n in (1, 2)}
# The run whose rate is the median (the lower middle one for an even count) stands for its rank count.
r = {n: sorted(runs[n], key=lambda x: x["load_cases"]["per_second"])[(repeats - 1) // 2] for n in (1, 2)}
out = {"preset": name, "full_load_cases": full, "slice": {"shapes": shapes, "load_cases_per_shape": loads}, "repeats": repeats,
       "rates_per_run": rates, "median_rate": rate, "runs": runs}
out["efficiency_2_ranks"] = rate[2] / (2 * rate[1])
out["projected_hours_full"] = {n: full / rate[n] / 3600 for n in (1, 2)}
out["projected_hours_2_ranks_range"] = [full / max(rates[2]) / 3600, full / min(rates[2]) / 3600]
# Where the 2-rank run loses against twice the 1-rank rate, from the median runs: the work done
# per load case (phase seconds summed over ranks; > 1: the ranks slow each other down, sharing
# the machine), and the time ranks sit idle at the end of the slice (shards are handed out one at
# a time: with 20 shapes in shards of 2, the last shard runs alone). The full Random2D has 125
# shards of the default 8 shapes, so its tail is a shard or less of an hour (under 1%).
busy = {n: sum(r[n]["seconds"]["phases_summed_over_groups"].values()) for n in (1, 2)}
out["work_per_load_case_2_vs_1"] = busy[2] / busy[1]
out["idle_share_2_ranks"] = 1 - busy[2] / (2 * r[2]["seconds"]["wall"])
work = {n: busy[n] / (shapes * loads) for n in (1, 2)}  # seconds per load case, summed over ranks
shard = preset.get("output", {}).get("shard_size", 8) * preset["loads"]["count"]  # load cases per shard
out["work_seconds_per_load_case"] = work
out["projected_hours_full_from_work"] = {n: (full * work[n] + (n - 1) * shard * work[n]) / n / 3600 for n in (1, 2)}
json.dump(out, open("results/bench_generate.json", "w"), indent=1)
print(f"{name} slice: {shapes} shapes x {loads} load cases, {repeats} runs per rank count (alternated)")
for n in (1, 2):
    print(f"{n} rank(s): load cases/s per run {', '.join(f'{x:.2f}' for x in rates[n])}; median {rate[n]:.2f}")
print("\nThe median run of each:")
print(f"| ranks | load cases/s | wall s | converged | failed | Newton it./case | peak RSS MiB/rank | full {name}, {full} load cases (h) |")
print("|---|---|---|---|---|---|---|---|")
for n in (1, 2):
    x = r[n]
    lc = x["load_cases"]["converged"] + x["load_cases"]["failed"]
    print(f"| {n} | {rate[n]:.2f} | {x['seconds']['wall']:.1f} | {x['load_cases']['converged']} | {x['load_cases']['failed']} "
          f"| {x['solver']['newton_iterations'] / max(lc, 1):.1f} | {', '.join(f'{m:.0f}' for m in x['peak_rss_mib_per_rank'])} "
          f"| {out['projected_hours_full'][n]:.2f} |")
print(f"2 ranks: {100 * out['efficiency_2_ranks']:.0f}% of twice the 1-rank rate (medians); full {name} on 2 ranks: "
      f"{out['projected_hours_full'][2]:.2f} h (runs: {out['projected_hours_2_ranks_range'][0]:.2f}-"
      f"{out['projected_hours_2_ranks_range'][1]:.2f} h)")
print(f"From the work (phase seconds per load case {work[1]:.3f} on 1 rank, {work[2]:.3f} on 2, spread over the ranks, "
      f"plus one shard of {shard} load cases alone at the end): full {name} {out['projected_hours_full_from_work'][1]:.2f} h "
      f"on 1 rank, {out['projected_hours_full_from_work'][2]:.2f} h on 2")
print(f"2 ranks lose {100 * (out['work_per_load_case_2_vs_1'] - 1):.1f}% to more work per load case (the ranks share "
      f"the machine) and {100 * out['idle_share_2_ranks']:.1f}% to time outside the phases (start-up, and the end of the slice: shards handed "
      f"out one at a time); without that tail: {100 / out['work_per_load_case_2_vs_1']:.0f}% of twice the 1-rank rate")
print("\nPhase split (seconds summed over ranks):")
print("| phase | 1 rank | share | 2 ranks | share |")
print("|---|---|---|---|---|")
ph = {n: r[n]["seconds"]["phases_summed_over_groups"] for n in (1, 2)}
tot = {n: sum(ph[n].values()) for n in (1, 2)}
for k in ph[1]:
    print(f"| {k} | {ph[1][k]:.1f} | {100 * ph[1][k] / tot[1]:.0f}% | {ph[2][k]:.1f} | {100 * ph[2][k] / tot[2]:.0f}% |")
for n in (1, 2):
    print(f"factorisations (PCSetUp) on {n} rank(s): {r[n]['seconds']['factorization_PCSetUp_summed_over_ranks']:.1f} s "
          f"= {100 * r[n]['seconds']['factorization_PCSetUp_summed_over_ranks'] / tot[n]:.0f}% of the phases")
print("JSON: results/bench_generate.json")
PY
