# Shared preamble of the CLI tests (sourced): the binary and source tree from CTest's
# environment, a scratch directory removed on exit, pass/fail counters, and finish (the summary
# line and the exit status), compare (two datasets).
set -u
bin=${HYPERSHAPE_BIN:?}
src=${HYPERSHAPE_SOURCE_DIR:?}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fails=0 passes=0
fail() { echo "FAIL: $*"; fails=$((fails+1)); }
ok() { echo "ok   $*"; passes=$((passes+1)); }
# Two dataset directories array by array (tests/cli/compare_datasets.py; --rtol R allowed).
compare() { /usr/bin/python3 "$src/tests/cli/compare_datasets.py" "$@"; }
finish() {
  echo "$passes passed, $fails failed"
  [ "$fails" -eq 0 ]
}
