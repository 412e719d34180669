#!/usr/bin/env bash
# What each accuracy bound costs (issue 19, docs/ACCURACY.md "What each bound costs"):
# one preset on one seed generated as it is (with its labels' estimates) and then asked for by
# accuracy (`accuracy: {rel_l2: B}`) at each bound B; per run the run report, the shards and the
# process's CPU seconds, then scripts/accuracy_table.py (table, JSON and the figure).
#   scripts/study_accuracy_levels.sh [PRESET] [SEED] [SHAPES] [LOADS]
#     defaults: easy_random2d 4242 8 25; BOUNDS="0.05 0.03 0.01" (the bounds, any order);
#     NP=2 (ranks); OUT=results/accuracy_levels/PRESET_SEED (the datasets, times.log, the table);
#     JSON=docs/accuracy_levels/PRESET_SEED.json and PNG=docs/figures/accuracy_levels_PRESET.png
#     (where the table's rows and its figure go); HYPERSHAPE=build/hypershape; BEFORE=an earlier
#     study's JSON (drawn dashed in the figure, named BEFORE_NAME); ACCURACY_KEYS=more keys of the
#     accuracy block (e.g. "start: rest").
# A run already complete is not generated again (the factory finds it complete), so a stopped
# study resumes where it was; its CPU seconds are those of the run that finished it.
set -euo pipefail
cd "$(dirname "$0")/.."
preset=${1:-easy_random2d} seed=${2:-4242} shapes=${3:-8} loads=${4:-25}
bounds=${BOUNDS:-0.05 0.03 0.01}
np=${NP:-2}
bin=${HYPERSHAPE:-build/hypershape}
out=${OUT:-results/accuracy_levels/${preset}_$seed}
json=${JSON:-docs/accuracy_levels/${preset}_$seed.json}
png=${PNG:-docs/figures/accuracy_levels_$preset.png}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1
[ -x "$bin" ] || { echo "study_accuracy_levels.sh: $bin not found (scripts/setup.sh builds it)" >&2; exit 2; }
[ -x /usr/bin/time ] || { echo "study_accuracy_levels.sh: /usr/bin/time not found (scripts/setup.sh installs it, or: apt-get install -y time)" >&2; exit 2; }
mkdir -p "$out" "$(dirname "$json")" "$(dirname "$png")"
runs=()
run() {  # $1 tag, $2 the accuracy line ("" = the preset as it is, with its estimates)
  local cfg="$out/$1.yaml"
  {
    echo "preset: $preset"
    echo "name: ${preset}_$1"
    echo "seed: $seed"
    echo "shapes: {count: $shapes}"
    echo "loads: {count: $loads}"
    echo "output: {shard_size: 1}"
    if [ -n "$2" ]; then echo "$2"; else echo "representations: {error_estimate: true}"; fi
  } > "$cfg"
  if [ ! -f "$out/$1/manifest.json" ] || ! grep -q '"complete": true' "$out/$1/manifest.json" 2>/dev/null; then
    echo "[study_accuracy_levels] $1: mpiexec -n $np $bin -q generate $cfg -o $out/$1" >&2
    /usr/bin/time -f "$1 cpu_user %U cpu_sys %S wall %e" -a -o "$out/times.log" \
      mpiexec -n "$np" "$bin" -q generate "$cfg" --progress 120 -o "$out/$1"
  fi
  runs+=("$out/$1")
}
run preset ""
for b in $bounds; do run "rel_l2_$b" "accuracy: {rel_l2: $b${ACCURACY_KEYS:+, $ACCURACY_KEYS}}"; done
before=()
[ -z "${BEFORE:-}" ] || before=(--before "$BEFORE" --before-name "${BEFORE_NAME:-before}")
/usr/bin/python3 scripts/accuracy_table.py "${runs[@]}" --times "$out/times.log" --json "$json" --plot "$png" "${before[@]}" \
  | tee "$out/table.md"
