#!/usr/bin/env bash
# README.md's examples do what it says, run as a reader would run them:
# - its C example is examples/quickstart/quickstart.c, byte for byte (the
#   install_example test builds and runs that file against an installed copy);
# - its exit codes are tools/hocad.c's;
# - after `cmake --install` to a temporary prefix (standing for the
#   README's $HOME/.local), its command-line examples run with the installed
#   hocad from a directory holding examples/models, and its Python command
#   prints the report's stages (skipped in a sanitizer build: Python cannot
#   load an instrumented library without the sanitizer runtime preloaded).
#   Without a `gmsh` on the PATH, the gmsh line is replaced by hocad's own
#   unoptimised order-3 mesh, so the optimize line still runs.
# Usage: readme_examples.sh BUILD_DIR SOURCE_DIR [sanitize]
# SPDX-License-Identifier: GPL-2.0-or-later
set -euo pipefail
build=$(cd "$1" && pwd) src=$(cd "$2" && pwd) sanitize=${3:-}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
pass=0 fail=0
check() { # check NAME COMMAND...: one test
  if "${@:2}"; then pass=$((pass + 1)); else echo "FAIL: $1"; fail=$((fail + 1)); fi
}
readme=$src/README.md

# block LANG HEADING: the first ```LANG block after the line "## HEADING"
block() {
  awk -v lang="$1" -v head="## $2" '
    $0 == head { in_section = 1; next }
    in_section && /^## / { exit }
    in_section && !inside && $0 == "```" lang { inside = 1; next }
    inside && $0 == "```" { exit }
    inside { print }' "$readme"
}

block c C >"$tmp/readme.c"
check "the C example is examples/quickstart/quickstart.c" \
  cmp "$tmp/readme.c" "$src/examples/quickstart/quickstart.c"

# every exit code of tools/hocad.c, as `N` in the README's exit codes
codes_documented() {
  local text code ok=0
  text=$(awk '/^Exit codes:/,/^$/' "$readme")
  for code in $(sed -n '/^enum {/,/^};/p' "$src/tools/hocad.c" | grep -o 'EXIT_[A-Z_]* = [0-9]*' |
                awk '{print $3}'); do
    grep -q "\`$code\`" <<<"$text" || { echo "exit code $code is not in the README"; ok=1; }
  done
  return $ok
}
check "the README lists every exit code of tools/hocad.c" codes_documented

prefix=$tmp/home/.local
cmake --install "$build" --prefix "$prefix" >"$tmp/install.log"
mkdir -p "$tmp/run/examples"
ln -s "$src/examples/models" "$tmp/run/examples/models"

# the command-line examples, one command a line, comments skipped
block sh "Command line" | grep -v '^#' >"$tmp/cli.sh"
check "three command-line examples" test "$(grep -c '^hocad ' "$tmp/cli.sh")" -ge 3
if ! command -v gmsh >/dev/null; then
  sed -i 's|^gmsh \([^ ]*\) .* -o \([^ ]*\)$|hocad mesh \1 --order 3 --no-optimize -o \2|' "$tmp/cli.sh"
fi
cli() {
  (cd "$tmp/run" && PATH=$prefix/bin:$PATH bash -euo pipefail "$tmp/cli.sh") >"$tmp/cli.log" 2>&1 ||
    { cat "$tmp/cli.log"; return 1; }
  local f
  for f in screw_p3.msh screw_p3.vtu r.json screw_opt.msh worst.png; do
    [ -s "$tmp/run/$f" ] || { echo "no $f"; return 1; }
  done
}
check "the command-line examples run and write their files" cli

python_example() {
  # the README's command, with the temporary prefix's home for $HOME
  block sh Python | sed -e :a -e '/\\$/N; s/\\\n//; ta' >"$tmp/py.sh"
  (cd "$src" && HOME=$tmp/home bash -euo pipefail "$tmp/py.sh") >"$tmp/py.log" 2>&1 ||
    { cat "$tmp/py.log"; return 1; }
  grep -Eq '^optimized +3 +350 .* 0 +[0-9.]+$' "$tmp/py.log" || { cat "$tmp/py.log"; return 1; }
}
if [ -z "$sanitize" ]; then
  check "the Python example prints the report of the installed package" python_example
fi
echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
