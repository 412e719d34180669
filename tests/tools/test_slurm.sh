#!/usr/bin/env bash
# scripts/slurm/generate.sbatch under a real SLURM (opt-in: CTest label `tools`, configuration
# `tools`; `ctest -C tools -R tools.slurm`). Starts a one-node cluster (munged, slurmctld, slurmd
# of Debian's munge and slurm-wlm, installed on demand; scripts/slurm/local_cluster.sh) in a
# scratch directory, then:
#  - `sbatch --array=0-2` of generate.sbatch over a 5-shape dataset (3 shards) and an index job
#    with --dependency=afterok on the array: every job COMPLETED with exit code 0, and the
#    dataset equals the one-process run bit for bit (tests/cli/compare_datasets.py);
#  - one job of 2 tasks with GROUP_SIZE=2: generate.sbatch runs a solver group of 2 ranks through
#    `srun --mpi=pmix`; the report says 2 ranks, and the dataset equals the one-process run to
#    1e-9 (a group sums in another order).
# Stops the daemons on exit. Needs root, HYPERSHAPE_BIN and HYPERSHAPE_SOURCE_DIR (set by CTest).
. "$(dirname "$0")/../cli/lib.sh"
cluster=$work/cluster
trap '"$src/scripts/slurm/local_cluster.sh" stop "$cluster"; rm -rf "$work"' EXIT
# Two free ports in a row for slurmctld/slurmd (another cluster may be up on the defaults).
SLURM_PORT=$(/usr/bin/python3 -c 'import socket
for p in range(16917, 17917, 2):
    try:
        ss = [socket.socket() for _ in range(2)]
        [s.bind(("127.0.0.1", p + i)) for i, s in enumerate(ss)]
        print(p); break
    except OSError: pass
    finally: [s.close() for s in ss]')
export SLURM_PORT
"$src/scripts/slurm/local_cluster.sh" start "$cluster" || { fail "cluster did not start"; finish; exit 1; }
export SLURM_CONF=$cluster/slurm.conf

cat > "$work/slurm.yaml" <<'YAML'
preset: random2d
name: slurm
seed: 11
shapes: {count: 5, h: 0.1}
loads: {count: 3}
representations: {grid_size: 16}
output: {shard_size: 2}
YAML
"$bin" -q generate "$work/slurm.yaml" --progress 0 -o "$work/ref" || fail "one-process reference"

# Waits until none of the given jobs is pending or running (at most $2 seconds).
wait_jobs() {
  local ids=$1 limit=$2
  for _ in $(seq "$limit"); do
    [ -z "$(squeue -h -j "$ids" -t PD,R,CG 2>/dev/null)" ] && return 0
    sleep 1
  done
  echo "jobs $ids still queued after $limit s:"; squeue
  return 1
}
# "JobState ExitCode" of every job (and array task) of a job id, one line each.
states() { scontrol -o show job "$1" | sed -E 's/.*JobState=([A-Z_]+).* ExitCode=([0-9:]+).*/\1 \2/'; }
all_completed() { ! states "$1" | grep -v '^COMPLETED 0:0$' | grep -q . && [ -n "$(states "$1")" ]; }

cd "$work"
export CONFIG=$work/slurm.yaml HYPERSHAPE_BIN=$bin
array=$(OUT=$work/array sbatch --parsable --array=0-2 --ntasks=1 --time=10 \
          --output="$work/array-%A_%a.out" "$src/scripts/slurm/generate.sbatch") || fail "sbatch --array"
index=$(sbatch --parsable --dependency=afterok:"$array" --ntasks=1 --time=5 --output="$work/index-%j.out" \
          --wrap "$bin index $work/array") || fail "sbatch index"
group=$(OUT=$work/group GROUP_SIZE=2 sbatch --parsable --ntasks=2 --time=10 \
          --output="$work/group-%j.out" "$src/scripts/slurm/generate.sbatch") || fail "sbatch group"
wait_jobs "$array,$index,$group" 240 || fail "jobs did not finish"

n_tasks=$(states "$array" | wc -l)
if all_completed "$array" && [ "$n_tasks" -eq 3 ]; then ok "array job $array: 3 tasks COMPLETED 0:0"
else fail "array job: $(states "$array" | tr '\n' ';')"; cat "$work"/array-*.out; fi
if all_completed "$index"; then ok "index job $index (afterok:$array) COMPLETED 0:0"
else fail "index job: $(states "$index")"; cat "$work"/index-*.out; fi
if compare "$work/ref" "$work/array"; then ok "3-task array + index job == one process, bit for bit"
else fail "array != one process"; fi
n_reports=0
for t in 0 1 2; do
  [ -f "$work/array/reports/task-00$t-of-003.json" ] && n_reports=$((n_reports + 1))
done
if [ "$n_reports" -eq 3 ]; then ok "a run report of each of the 3 array tasks (reports/task-00I-of-003.json)"
else fail "$n_reports of 3 array task reports"; ls "$work/array/reports"; fi

if all_completed "$group"; then ok "group job $group (2 tasks, srun --mpi=pmix) COMPLETED 0:0"
else fail "group job: $(states "$group")"; cat "$work"/group-*.out; fi
if grep -q "2 ranks in groups of 2" "$work"/group-*.out; then ok "srun started 2 ranks in one solver group of 2"
else fail "no '2 ranks in groups of 2' in the group job's output"; cat "$work"/group-*.out; fi
if compare "$work/ref" "$work/group" --rtol 1e-9; then ok "solver group of 2 under srun == one process, to 1e-9"
else fail "group of 2 != one process"; fi
finish
