#!/usr/bin/env bash
# hocad under valgrind: no invalid access, no leak of ours, on a mesh run,
# a quality run and a failing run.
# usage: cli_valgrind.sh HOCAD SOURCE_DIR
set -u
hocad=$(readlink -f "$1")
src=$(readlink -f "$2")
if ! command -v valgrind >/dev/null; then
  echo "valgrind is not installed (scripts/deps.sh --test installs it)"
  echo "0 passed, 1 failed"
  exit 1
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
pass=0
fail=0
vg() {
  local what=$1
  shift
  OMP_NUM_THREADS=1 valgrind -q --error-exitcode=99 --leak-check=full --show-leak-kinds=definite \
    --errors-for-leak-kinds=definite --suppressions="$src/tests/valgrind.supp" "$hocad" "$@" \
    > out.txt 2> err.txt
  local rc=$?
  if [ $rc -ne 99 ] && ! grep -q "==[0-9]*==" err.txt; then
    pass=$((pass + 1))
  else
    fail=$((fail + 1))
    echo "FAIL: $what (exit $rc)" >&2
    head -40 err.txt >&2
  fi
}
model=$src/examples/models/screw.step
vg "mesh" mesh "$model" --order 2 --curvature 6 -o s.msh --vtu s.vtu --json s.json -q
vg "quality" quality "$model" s.msh -q
vg "optimize" optimize "$model" s.msh -o s2.msh -q
vg "missing model" mesh nosuch.step --order 2 --no-output
vg "bad order" mesh "$model" --order 0
echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
