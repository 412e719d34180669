#!/usr/bin/env bash
# Shards record the numerics platform that wrote them (software/numerics: glibc's libm path and
# OpenBLAS's kernel family, which change the data's last bits), and `hypershape index` warns
# when a dataset's shards come from different ones (README, "On machines of different kinds").
# The second kind is made on this machine by masking glibc's FMA path for one SLURM-style task;
# on a CPU without FMA and AVX2 both tasks are of one kind, and the mixed case is skipped.
. "$(dirname "$0")/lib.sh"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OPENBLAS_NUM_THREADS=1
cat > "$work/c.yaml" <<YAML
preset: random2d_p1
shapes: {count: 2, h: 0.1}
loads: {count: 2}
output: {shard_size: 1}
YAML
attr() { /usr/bin/python3 -c "import h5py, sys; v = h5py.File(sys.argv[1])['software'].attrs['numerics']; print(v.decode() if isinstance(v, bytes) else v)" "$1"; }
manifest_kinds() { /usr/bin/python3 -c "import json, sys; print(len(json.load(open(sys.argv[1])).get('numerics_platforms', {})))" "$1"; }

# One machine, two tasks: no warning, no numerics_platforms in the manifest.
for t in 0 1; do "$bin" -q generate "$work/c.yaml" -o "$work/same" --task-index $t --task-count 2 2>>"$work/same.err"; done
a=$(attr "$work/same/shards/shard-000000.h5") b=$(attr "$work/same/shards/shard-000001.h5")
if [[ "$a" == glibc*libm*";"* && "$a" == "$b" ]]; then ok "shards record the platform: $a"; else fail "software/numerics: '$a', '$b'"; fi
if ! grep -q "machines of different kinds" "$work/same.err" && [ "$(manifest_kinds "$work/same/manifest.json")" = 0 ]; then
  ok "one kind: no warning, no numerics_platforms"
else
  fail "one kind: $(cat "$work/same.err")"
fi

# Task 1 with glibc's FMA variants masked.
"$bin" -q generate "$work/c.yaml" -o "$work/mixed" --task-index 0 --task-count 2 2>/dev/null
GLIBC_TUNABLES=glibc.cpu.hwcaps=-FMA "$bin" -q generate "$work/c.yaml" -o "$work/mixed" --task-index 1 --task-count 2 2>/dev/null
c=$(attr "$work/mixed/shards/shard-000001.h5")
if [ "$c" = "$a" ]; then
  ok "skipped: this CPU takes no FMA path in glibc's libm ($a)"
elif [[ "$c" == *"libm no-fma"* ]]; then
  if "$bin" index "$work/mixed" 2>"$work/mixed.err" && grep -q "machines of different kinds" "$work/mixed.err" \
     && [ "$(manifest_kinds "$work/mixed/manifest.json")" = 2 ]; then
    ok "mixed kinds: index warns and the manifest lists both"
  else
    fail "mixed kinds: $(cat "$work/mixed.err")"
  fi
else
  fail "masked task recorded '$c'"
fi
finish
