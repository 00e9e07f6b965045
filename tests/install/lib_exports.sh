#!/usr/bin/env bash
# libhocad.so exports exactly the functions include/hocad.h declares: each
# of them, and no other symbol (no unprefixed name, no internal hoc_*
# function). The declared functions come from the compiler (gcc -aux-info),
# not from the regular expression that wrote the version script
# (cmake/exports.cmake), so a declaration that script misses fails here.
# Usage: lib_exports.sh LIBHOCAD.so HOCAD.h C_COMPILER
# SPDX-License-Identifier: GPL-2.0-or-later
set -euo pipefail
lib=$1 header=$2 cc=$3
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
pass=0 fail=0
check() { # check NAME COMMAND...: one test
  if "${@:2}"; then pass=$((pass + 1)); else echo "FAIL: $1"; fail=$((fail + 1)); fi
}

nm -D --defined-only "$lib" | awk 'NF == 3 {print $3}' | sed 's/@.*//' | sort -u >"$tmp/exported"
echo '#include "hocad.h"' >"$tmp/h.c"
"$cc" -I"$(dirname "$header")" -aux-info "$tmp/aux" -fsyntax-only "$tmp/h.c"
grep -o '\bhoc_[a-z0-9_]* (' "$tmp/aux" | sed 's/ ($//' | sort -u >"$tmp/declared"

echo "$(wc -l <"$tmp/exported") symbols exported, $(wc -l <"$tmp/declared") functions declared"
unprefixed() { ! grep -v '^hoc_' "$tmp/exported"; }
check "every exported symbol starts with hoc_" unprefixed
check "at least 50 functions declared" test "$(wc -l <"$tmp/declared")" -ge 50
missing() { ! comm -23 "$tmp/declared" "$tmp/exported" | grep .; }
check "every declared function is exported (missing above)" missing
extra() { ! comm -13 "$tmp/declared" "$tmp/exported" | grep .; }
check "nothing but the declared functions is exported (extra above)" extra
soname() { readelf -d "$lib" | grep -q 'SONAME.*libhocad\.so\.[0-9]'; }
check "the library has a versioned soname" soname
# what the library links it records itself (a program links -lhocad alone)
for dep in libgmsh libgomp libpng libm; do
  needed() { readelf -d "$lib" | grep -q "NEEDED.*\[$1[0-9]*\.so"; }
  check "libhocad.so records $dep" needed "$dep"
done
echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
