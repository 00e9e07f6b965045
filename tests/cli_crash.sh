#!/usr/bin/env bash
# A crash inside gmsh is not a crash of hocad: the importer's segfault on a
# malformed STEP file ends with one line and exit 2, the mesher's abort on
# the spring with the faces that crash it left out (exit 4, the rest
# written); Ctrl-C while gmsh's mesher runs in its child process ends both.
# usage: cli_crash.sh HOCAD SOURCE_DIR
set -u
hocad=$(readlink -f "$1")
src=$(readlink -f "$2")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
pass=0
fail=0
ok() { if eval "$2"; then pass=$((pass + 1)); else fail=$((fail + 1)); echo "FAIL: $1" >&2; fi; }

"$hocad" mesh "$src/tests/data/square_dangling_vector.step" --order 2 -o bad.msh -q 2> err.txt
rc=$?
ok "importer crash: exit 2 (got $rc)" "[ $rc -eq 2 ]"
ok "importer crash: one line" "[ \$(wc -l < err.txt) -eq 1 ]"
ok "importer crash: says so" "grep -q \"gmsh's importer crashed (SIGSEGV)\" err.txt"
ok "importer crash: no output" "[ ! -e bad.msh ]"
cat err.txt

"$hocad" mesh "$src/tests/data/spring_helix.igs" --order 2 -o spring.msh -q 2> err.txt
rc=$?
ok "mesher crash: exit 4 (got $rc)" "[ $rc -eq 4 ]"
ok "mesher crash: faces left out" "grep -q 'could not be meshed' err.txt"
ok "mesher crash: the rest written" "[ -s spring.msh ] && grep -q '\$Elements' spring.msh"
cat err.txt

# a face gmsh's mesher does not finish (it inserts points for ever on the
# wing's face): skipped after --mesher-timeout, the caps written (exit 4)
"$hocad" mesh "$src/tests/data/wing_rounded_te.brep" --order 2 --mesher-timeout 2 -o wing.msh \
  -q 2> err.txt
rc=$?
ok "mesher timeout: exit 4 (got $rc)" "[ $rc -eq 4 ]"
ok "mesher timeout: says so" "grep -q 'faces 1; gmsh.s mesher did not finish 1 of them in 2 s' err.txt"
ok "mesher timeout: the rest written" "[ -s wing.msh ] && grep -q '\$Elements' wing.msh"
cat err.txt

# Ctrl-C (to hocad alone) while the mesher's child runs: hocad exits 130,
# its child ends with it (it dies with its parent), no output is written
"$hocad" mesh "$src/tests/data/spring_helix.igs" --order 2 -o int.msh > log.txt 2> /dev/null &
pid=$!
# past the import (its own child) once the model's line is printed
for _ in $(seq 1 400); do
  grep -q '^model ' log.txt && break
  sleep 0.05
done
child=
for _ in $(seq 1 200); do
  child=$(cat /proc/$pid/task/*/children 2> /dev/null | tr -s ' \n' ' ' | sed 's/ *$//')
  [ -n "$child" ] && break
  sleep 0.05
done
ok "a child process runs the mesher" "[ -n \"$child\" ]"
kill -INT $pid
wait $pid
rc=$?
ok "interrupted: exit 130 (got $rc)" "[ $rc -eq 130 ]"
gone=1
for c in $child; do
  for _ in $(seq 1 100); do
    [ -e /proc/$c ] || break
    sleep 0.05
  done
  [ -e /proc/$c ] && gone=0
done
ok "interrupted: the child ended too" "[ $gone -eq 1 ]"
ok "interrupted: no output" "[ ! -e int.msh ]"
ok "no temporary files" "[ -z \"\$(ls -A | grep tmp- || true)\" ]"
echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
