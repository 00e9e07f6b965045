#!/usr/bin/env bash
# Ctrl-C during a run: exit code 130, the previous output intact, no
# temporary file left behind.
# usage: cli_interrupt.sh HOCAD SOURCE_DIR
set -u
hocad=$(readlink -f "$1")
src=$(readlink -f "$2")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
pass=0
fail=0
ok() { if eval "$2"; then pass=$((pass + 1)); else fail=$((fail + 1)); echo "FAIL: $1" >&2; fi; }
echo previous > out.msh
# a run long enough to be interrupted in the middle (order 5 on the gear)
"$hocad" mesh "$src/examples/models/gear_f360.step" --order 5 -o out.msh -q &
pid=$!
sleep 3
kill -INT $pid
wait $pid
rc=$?
ok "exit code 130 (got $rc)" "[ $rc -eq 130 ]"
ok "previous output intact" "[ \"\$(cat out.msh)\" = previous ]"
ok "no temporary files" "[ -z \"\$(ls -A | grep tmp- || true)\" ]"
echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
