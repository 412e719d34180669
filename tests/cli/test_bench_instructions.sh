#!/usr/bin/env bash
# scripts/bench_instructions.sh: a missing or non-executable other build is refused by name
# (exit 2, nothing run); without valgrind the script says what to install (exit 2). With valgrind
# (optional, not installed by setup.sh), the binary against itself on one Random2D load case:
# the table printed, the same instructions in total and in the solves (callgrind's counts of one
# binary agree between runs to about 1e-5), the datasets identical, the JSON written. gmsh's own
# count moves more between runs (1.4e-3 in one CI run: its containers of mesh entities are ordered
# by address), so the mesh piece is held to 1e-2 and every other piece to 1e-3.
source "$(dirname "$0")/lib.sh"
script="$src/scripts/bench_instructions.sh"
out=$(THIS_HYPERSHAPE="$bin" "$script" "$work/no-such-build" 2>&1); rc=$?
[ $rc -eq 2 ] && ok "a missing other build: exit 2" || fail "a missing other build: exit $rc"
if command -v valgrind > /dev/null; then
  grep -q "no-such-build is not an executable" <<<"$out" && ok "the path named" || fail "message: $out"
  cp "$bin" "$work/other-hypershape"
  cd "$work" && mkdir -p src && cp -r "$src/scripts" "$src/tests" src/ && ln -s "$(dirname "$bin")" src/build
  if THIS_HYPERSHAPE="$bin" src/scripts/bench_instructions.sh "$work/other-hypershape" 1 1 > table.txt 2>&1; then
    ok "the binary against itself"
  else
    fail "exit $?"; cat table.txt
  fi
  grep -q "arrays: identical" table.txt && ok "datasets identical" || fail "datasets: $(head -1 table.txt)"
  grep -q "^| whole process | .* | 1.000 |$" table.txt && ok "the same instructions in total" || fail "$(grep whole table.txt)"
  grep -q "^| load cases: solve_for_target | .* | 1.000 |$" table.txt && ok "the same in the solves" || fail "$(grep solve_for table.txt)"
  /usr/bin/python3 -c "
import json; j = json.load(open('src/results/bench_instructions.json'))
c = j['instructions']; assert c['this'].keys() == c['other'].keys() and c['this']['whole process'] > 0, c
for k, a in c['this'].items():
    b = c['other'][k]
    assert a and b and abs(a / b - 1) < (1e-2 if k == 'mesh (gmsh)' else 1e-3), (k, a, b)" \
    && ok "JSON: both builds' counts, within 1e-3 of each other (gmsh's 1e-2)" || fail "JSON"
else
  grep -q "needs valgrind" <<<"$out" && ok "without valgrind: says what to install" || fail "message: $out"
fi
finish
