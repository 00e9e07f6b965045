#!/usr/bin/env bash
# `cmake --install` to a temporary prefix, then the quickstart example
# (examples/quickstart) built against that installed copy as an outside
# program would build it: with `pkg-config --cflags --libs hocad` (the
# shared library alone), with `pkg-config --static` (a copy of the prefix
# without the shared library, which also shows the installation can move),
# and as a CMake project with find_package(hocad) (hocad::hocad and
# hocad::hocad_static). Each program meshes a bundled model at order 3; its
# .msh must match the others' byte for byte, and the installed `hocad
# quality` must find in it the elements, min q and tangled count of the
# program's last Table 2 row.
# Usage: install_example.sh BUILD_DIR SOURCE_DIR C_COMPILER [EXTRA_CFLAGS]
# (EXTRA_CFLAGS: -fsanitize=... for a sanitizer build, whose library needs
# the sanitizer runtime linked into the program).
# SPDX-License-Identifier: GPL-2.0-or-later
set -euo pipefail
build=$(cd "$1" && pwd) src=$(cd "$2" && pwd) cc=$3 extra=${4:-}
model=$src/examples/models/screw.step
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
prefix=$tmp/prefix
pass=0 fail=0
check() { # check NAME COMMAND...: one test
  if "${@:2}"; then pass=$((pass + 1)); else echo "FAIL: $1"; fail=$((fail + 1)); fi
}

cmake --install "$build" --prefix "$prefix" >"$tmp/install.log"
for f in bin/hocad include/hocad.h lib/libhocad.a lib/libhocad.so lib/pkgconfig/hocad.pc \
         lib/cmake/hocad/hocadConfig.cmake lib/cmake/hocad/hocadConfigVersion.cmake \
         lib/cmake/hocad/hocadTargets.cmake; do
  check "installed $f" test -e "$prefix/$f"
done
check "installed hocad --version" "$prefix/bin/hocad" --version

# run NAME PROGRAM: mesh the model; keep its table and its .msh
run() {
  "$2" "$model" "$tmp/$1.msh" >"$tmp/$1.out" 2>"$tmp/$1.err" || { cat "$tmp/$1.err"; return 1; }
  cat "$tmp/$1.out"
}
# quality_agrees NAME: `hocad quality` of the .msh finds the last row's numbers
quality_agrees() {
  "$prefix/bin/hocad" quality "$model" "$tmp/$1.msh" >"$tmp/$1.quality" 2>/dev/null
  local row input
  row=$(tail -1 "$tmp/$1.out" | awk '{print $2, $3, $4, $6}')
  input=$(awk '$1 == "input" {print $2, $3, $4, $8}' "$tmp/$1.quality")
  [ -n "$row" ] && [ "$row" = "$input" ] || { echo "table: $row; hocad quality: $input"; return 1; }
}
# needs_libhocad PROGRAM: 0 if it loads libhocad.so
needs_libhocad() { readelf -d "$1" | grep -q 'NEEDED.*libhocad\.so'; }
not_needs_libhocad() { ! needs_libhocad "$1"; }

export PKG_CONFIG_PATH=$prefix/lib/pkgconfig
# shellcheck disable=SC2046,SC2086  # the flags are words
check "pkg-config: compile and link" \
  $cc $extra "$src/examples/quickstart/quickstart.c" -o "$tmp/pc_shared" $(pkg-config --cflags --libs hocad)
check "pkg-config: the program loads libhocad.so" needs_libhocad "$tmp/pc_shared"
export LD_LIBRARY_PATH=$prefix/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
check "pkg-config: run" run pc_shared "$tmp/pc_shared"
check "pkg-config: hocad quality agrees" quality_agrees pc_shared

cp -a "$prefix" "$tmp/static"
rm -f "$tmp"/static/lib/libhocad.so*
export PKG_CONFIG_PATH=$tmp/static/lib/pkgconfig
# shellcheck disable=SC2046,SC2086
check "pkg-config --static: compile and link (moved prefix)" \
  $cc $extra "$src/examples/quickstart/quickstart.c" -o "$tmp/pc_static" $(pkg-config --cflags --libs --static hocad)
check "pkg-config --static: no libhocad.so" not_needs_libhocad "$tmp/pc_static"
check "pkg-config --static: run" run pc_static "$tmp/pc_static"
check "pkg-config --static: same .msh" cmp "$tmp/pc_shared.msh" "$tmp/pc_static.msh"

unset PKG_CONFIG_PATH
check "find_package: configure" cmake -S "$src/examples/quickstart" -B "$tmp/cmake" \
  -DCMAKE_C_COMPILER="$cc" -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_BUILD_TYPE=Release \
  "-DCMAKE_C_FLAGS=$extra" "-DCMAKE_EXE_LINKER_FLAGS=$extra" -DCMAKE_SKIP_RPATH=ON
check "find_package: build" cmake --build "$tmp/cmake"
check "find_package: hocad::hocad loads libhocad.so" needs_libhocad "$tmp/cmake/quickstart"
check "find_package: hocad::hocad_static does not" not_needs_libhocad "$tmp/cmake/quickstart_static"
check "find_package: run hocad::hocad" run cm_shared "$tmp/cmake/quickstart"
check "find_package: run hocad::hocad_static" run cm_static "$tmp/cmake/quickstart_static"
check "find_package: same .msh (shared)" cmp "$tmp/pc_shared.msh" "$tmp/cm_shared.msh"
check "find_package: same .msh (static)" cmp "$tmp/pc_shared.msh" "$tmp/cm_static.msh"
# another version's request is refused (hocadConfigVersion.cmake)
mkdir -p "$tmp/v9"
printf 'cmake_minimum_required(VERSION 3.18)\nproject(v LANGUAGES C)\nfind_package(hocad 9.0 REQUIRED)\n' \
  >"$tmp/v9/CMakeLists.txt"
refused() { ! cmake -S "$tmp/v9" -B "$tmp/v9/b" -DCMAKE_PREFIX_PATH="$prefix" >/dev/null 2>&1; }
check "find_package(hocad 9.0) is refused" refused
# a bad model: a clean error, exit 1, no output
bad() {
  : >"$tmp/empty.step"
  "$tmp/pc_shared" "$tmp/empty.step" "$tmp/bad.msh" 2>"$tmp/bad.err"
  local rc=$?
  cat "$tmp/bad.err"
  [ "$rc" -eq 1 ] && grep -q "empty" "$tmp/bad.err" && [ ! -e "$tmp/bad.msh" ]
}
check "an empty model fails cleanly" bad
echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
