#!/usr/bin/env bash
# One writer per dataset, a resume that verifies, clean signals, reproducible bytes (issue 20):
#  - two identical runs give byte-identical shards (cmp) and equal manifests' CRC-32;
#  - a second `generate` on a directory being written is refused, naming the holder, and the
#    dataset ends intact (equal to a clean run); two tasks of one array run side by side, a run
#    with another --task-count is refused; a lock left by kill -9 is taken over;
#  - a resume over damaged shards (bytes flipped inside a compressed block, a shard copied over
#    another, one truncated, one without its record, one of another dataset) redoes each with a
#    line saying why; `check` passes and the dataset equals a clean run byte for byte; `index`
#    refuses a damaged shard;
#  - the same config reformatted, reordered, or with defaults written out resumes the dataset
#    (identity by meaning);
#  - SIGTERM and SIGINT mid-run: a message, exit 128+signal, no temporary or lock file, and the
#    same command completes a dataset identical to a clean run.
# Needs HYPERSHAPE_BIN and HYPERSHAPE_SOURCE_DIR (set by CTest).
. "$(dirname "$0")/lib.sh"
compare() { /usr/bin/python3 "$src/tests/cli/compare_datasets.py" "$@" >/dev/null; }
check() { /usr/bin/python3 "$src/scripts/hypershape_data.py" check "$1" >/dev/null; }
same_bytes() {  # every shard and record of $1 equal to $2's
  local f
  for f in "$1"/shards/*.h5 "$1"/records/*.json; do cmp -s "$f" "$2/${f#"$1"/}" || return 1; done
  [ "$(ls "$1/shards" | wc -l)" -eq "$(ls "$2/shards" | wc -l)" ]
}

cat > "$work/ds.yaml" <<'YAML'
preset: random2d
name: writers
seed: 11
shapes: {count: 8, h: 0.15}
loads: {count: 2}
representations: {grid_size: 16}
output: {shard_size: 1}
YAML
gen() { "$bin" -q generate "$1" --progress 0 -o "$2" "${@:3}"; }
# in the background, $! the binary's own pid (a function would put a subshell in between)
bg() { "$bin" -q generate "$1" --progress 0 -o "$2" "${@:3}" & }

# ---- reproducible bytes -----------------------------------------------------------------------
gen "$work/ds.yaml" "$work/ref" || fail "reference run"
gen "$work/ds.yaml" "$work/ref2" || fail "second run"
if same_bytes "$work/ref" "$work/ref2" && [ "$(grep -o '"crc32": "[0-9a-f]*"' "$work/ref/manifest.json")" = \
     "$(grep -o '"crc32": "[0-9a-f]*"' "$work/ref2/manifest.json")" ]; then
  ok "two identical runs: byte-identical shards, equal CRC-32 in the manifests"
else fail "two identical runs differ in bytes"; fi

# ---- the lock -----------------------------------------------------------------------------------
sed -e 's/count: 8, h: 0.15/count: 10, h: 0.12/' "$work/ds.yaml" > "$work/long.yaml"
wait_for() { for _ in $(seq 1 400); do compgen -G "$1" >/dev/null && return 0; sleep 0.05; done; return 1; }
bg "$work/long.yaml" "$work/busy"; pid=$!
wait_for "$work/busy/.locks/task-0-of-1.lock" || fail "no lock file appeared"
t0=$(date +%s%N)
msg=$("$bin" generate "$work/long.yaml" --progress 0 -o "$work/busy" 2>&1 >/dev/null); code=$?
ms=$(( ($(date +%s%N) - t0) / 1000000 ))
if [ "$code" -eq 2 ] && grep -q "is being written by another run (host $(hostname), pid $pid, task 0 of 1" <<<"$msg"; then
  ok "second writer refused in $ms ms: $(tail -1 <<<"$msg" | cut -c1-150)"
else fail "second writer: exit $code: $msg"; fi
wait "$pid" || fail "the first writer failed"
gen "$work/long.yaml" "$work/long_ref" || fail "long reference"
if compare "$work/busy" "$work/long_ref" && check "$work/busy" && [ ! -e "$work/busy/.locks/task-0-of-1.lock" ]; then
  ok "the dataset is intact (equal to a clean run, check passes), the lock released"
else fail "the dataset written beside a refused writer differs or the lock is left"; fi
# Two tasks of one array side by side; a run with another task count is refused meanwhile.
bg "$work/long.yaml" "$work/array" --task-index 0 --task-count 2; p0=$!
wait_for "$work/array/.locks/task-0-of-2.lock"
bg "$work/long.yaml" "$work/array" --task-index 1 --task-count 2; p1=$!
wait_for "$work/array/.locks/task-1-of-2.lock"
msg=$("$bin" generate "$work/long.yaml" --progress 0 -o "$work/array" 2>&1 >/dev/null); code=$?
[ "$code" -eq 2 ] && grep -q "whose --task-count is not 1" <<<"$msg" && ok "a 1-task run is refused beside a 2-task array" ||
  fail "overlapping task counts: exit $code: $msg"
wait "$p0" && wait "$p1" && "$bin" -q index "$work/array" >/dev/null || fail "array tasks side by side"
compare "$work/array" "$work/long_ref" && ok "two array tasks wrote side by side: equal to one run" || fail "array differs"
# kill -9 leaves the lock file; nobody holds it: the next run takes it over.
bg "$work/long.yaml" "$work/stale"; pid=$!
wait_for "$work/stale/shards/shard-000001.h5"; kill -9 "$pid"; wait "$pid" 2>/dev/null
[ -e "$work/stale/.locks/task-0-of-1.lock" ] || echo "note: the killed run left no lock file"
msg=$("$bin" generate "$work/long.yaml" --progress 0 -o "$work/stale" 2>&1); code=$?
if [ "$code" -eq 0 ] && compare "$work/stale" "$work/long_ref"; then
  ok "after kill -9: the lock is taken over$(grep -o 'took over the stale lock[^(]*' <<<"$msg" | head -1 | sed 's/^/ (/;s/$/)/'), the dataset completed"
else fail "stale lock: exit $code: $msg"; fi

# ---- a resume that verifies -------------------------------------------------------------------
cp -r "$work/ref" "$work/dmg"
/usr/bin/python3 - "$work/dmg" <<'PY'
import shutil, sys
d = sys.argv[1] + "/shards/"
b = bytearray(open(d + "shard-000001.h5", "rb").read())      # inside a compressed block
for i in range(len(b) // 2, len(b) // 2 + 16): b[i] ^= 0x5A
open(d + "shard-000001.h5", "wb").write(b)
shutil.copy(d + "shard-000000.h5", d + "shard-000002.h5")       # a shard copied over another
open(d + "shard-000003.h5", "r+b").truncate(1000)                # a truncated one
PY
rm "$work/dmg/records/shard-000004.json"                         # no record of its checksum
cp "$work/long_ref/shards/shard-000005.h5" "$work/dmg/shards/"   # another dataset's shard 5
msg=$("$bin" index "$work/dmg" 2>&1); code=$?
[ "$code" -ne 0 ] && grep -q "shard-000001.h5: damaged" <<<"$msg" && ok "index refuses a damaged shard: $(tail -1 <<<"$msg" | cut -c1-140)" ||
  fail "index on damaged shards: exit $code: $msg"
msg=$("$bin" generate "$work/ds.yaml" --progress 0 -o "$work/dmg" 2>&1); code=$?
n_redo=$(grep -c ": redoing it" <<<"$msg")
for why in "shard-000001.h5: damaged" "shard-000002.h5: damaged" "shard-000003.h5: damaged" \
           "shard-000004.h5: no readable record" "shard-000005.h5: damaged"; do
  grep -q "$why" <<<"$msg" || fail "resume does not say '$why': $msg"
done
if [ "$code" -eq 0 ] && [ "$n_redo" -eq 5 ] && grep -q "(3 done before, 5 to do" <<<"$msg" && check "$work/dmg" &&
   same_bytes "$work/dmg" "$work/ref" && compare "$work/dmg" "$work/ref"; then
  ok "resume redid the 5 damaged or misplaced shards, kept 3: check passes, byte-identical to a clean run"
else fail "resume over damaged shards: exit $code, $n_redo redone: $msg"; fi

# ---- identity by meaning ----------------------------------------------------------------------
cat > "$work/same.yaml" <<'YAML'
# the same dataset, reformatted, reordered, defaults written out
output:
  shard_size: 1
representations: {grid_size: 16, grid: true, point_cloud: true}
loads:
  target: [0.1, 0.5]
  count: 2
shapes:
  h: 0.15
  count: 8
seed: 11
name: writers
solver: {rtol: 1.0e-9}
preset: random2d
YAML
cp -r "$work/ref" "$work/meaning" && rm "$work/meaning"/shards/shard-00000[4-7].h5 "$work/meaning/manifest.json"
# what an index step killed mid-write leaves (a pid that cannot exist): removed by the next run
echo '{"half": ' > "$work/meaning/manifest.json.tmp-4194999"
msg=$("$bin" generate "$work/same.yaml" --progress 0 -o "$work/meaning" 2>&1); code=$?
if [ "$code" -eq 0 ] && grep -q "(4 done before, 4 to do" <<<"$msg" && same_bytes "$work/meaning" "$work/ref" &&
   [ ! -e "$work/meaning/manifest.json.tmp-4194999" ]; then
  ok "the same config reformatted, reordered, defaults written out: resumed, byte-identical (a dead run's temporary manifest removed)"
else fail "identity by meaning: exit $code: $msg"; fi

# ---- signals ----------------------------------------------------------------------------------
for sig in TERM INT; do
  d="$work/sig$sig"
  "$bin" generate "$work/long.yaml" --progress 0 -o "$d" >/dev/null 2>"$work/sig.err" & pid=$!
  wait_for "$d/shards/shard-000001.h5"
  kill -$sig "$pid"; wait "$pid"; code=$?
  want=$((128 + $(kill -l $sig)))
  left=$(find "$d" -name '*.tmp*' -o -name '*.lock' | wc -l)
  if [ "$code" -eq "$want" ] && grep -q "\[generate\] stopped by SIG$sig: complete shards are kept" "$work/sig.err" &&
     [ "$left" -eq 0 ]; then
    ok "SIG$sig: exit $code, '$(cut -c1-90 "$work/sig.err")', no temporary or lock file"
  else fail "SIG$sig: exit $code (want $want), $left files left: $(cat "$work/sig.err")"; fi
  gen "$work/long.yaml" "$d" && compare "$d" "$work/long_ref" && same_bytes "$d" "$work/long_ref" &&
    ok "after SIG$sig the same command completes the dataset, byte-identical to a clean run" || fail "resume after SIG$sig"
done
finish
