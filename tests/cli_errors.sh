#!/usr/bin/env bash
# Bad input gets one clear line on stderr, a documented non-zero exit code,
# and leaves nothing on disk.
# usage: cli_errors.sh HOCAD SOURCE_DIR
set -u
hocad=$(readlink -f "$1")
src=$(readlink -f "$2")
model=$src/examples/models/screw.step
pass=0
fail=0
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"

# expect CODE DESCRIPTION -- ARGS...: exit code, exactly one stderr line
# starting with "hocad: error:", no new files in the directory
expect() {
  local code=$1 what=$2
  shift 3
  local before after
  before=$(ls -A | sort)
  "$hocad" "$@" >out.txt 2>err.txt
  local got=$?
  after=$(ls -A | grep -v -x -e out.txt -e err.txt | sort)
  local lines
  lines=$(grep -c . err.txt)
  if [ "$got" -eq "$code" ] && [ "$lines" -eq 1 ] && grep -q "^hocad: error: " err.txt &&
     [ "$before" = "$(echo "$after" | grep -v -x -e '' || true)" -o -z "$after" ]; then
    pass=$((pass + 1))
  else
    fail=$((fail + 1))
    echo "FAIL: $what: exit $got (want $code), stderr:" >&2
    cat err.txt >&2
    [ -n "$after" ] && echo "  files left: $after" >&2
  fi
  rm -f out.txt err.txt
}

: > empty.step
head -c 3000 "$src/examples/models/gear_f360.step" > truncated.step
head -c 4096 /dev/urandom > garbage.step
echo "just text" > notcad.txt
mkdir adir.step
rm -f empty.step.tmp
expect 2 "missing model" -- mesh nosuch.step --order 3 --no-output
expect 2 "empty model" -- mesh empty.step --order 3 --no-output
expect 2 "truncated model" -- mesh truncated.step --order 3 --no-output
expect 2 "garbage model" -- mesh garbage.step --order 3 --no-output
expect 2 "not a CAD file" -- mesh notcad.txt --order 3 --no-output
expect 2 "a directory" -- mesh adir.step --order 3 --no-output
expect 1 "order 0" -- mesh "$model" --order 0
expect 1 "order 99" -- mesh "$model" --order 99
expect 1 "order not a number" -- mesh "$model" --order three
expect 1 "msh version 3" -- mesh "$model" --order 2 --msh-version 3
expect 1 "msh version without value" -- mesh "$model" --order 2 --msh-version
expect 1 "negative size" -- mesh "$model" --size -1
expect 1 "size not a number" -- mesh "$model" --size abc
expect 1 "size NaN" -- mesh "$model" --size nan
expect 1 "size infinite" -- mesh "$model" --size inf
expect 1 "curvature zero" -- mesh "$model" --curvature 0
expect 1 "size factor zero" -- mesh "$model" --size-factor 0
expect 1 "size and size factor" -- mesh "$model" --size 5 --size-factor 2
expect 1 "size factor under size-min" -- mesh "$model" --size-factor 2 --size-min 100
expect 1 "mesher timeout zero" -- mesh "$model" --mesher-timeout 0
expect 1 "repair time zero" -- mesh "$model" --repair-time 0
expect 1 "repair time not a number" -- optimize "$model" in.msh -o out.msh --repair-time nan
expect 1 "refinements negative" -- mesh "$model" --refinements -1
expect 1 "refinements too many" -- mesh "$model" --refinements 11
expect 1 "optimize refinements too many" -- optimize "$model" in.msh -o out.msh --refinements 11
expect 1 "unknown option" -- mesh "$model" --frobnicate
expect 1 "missing value" -- mesh "$model" --order
expect 1 "unknown node set" -- mesh "$model" --nodes random
expect 1 "unknown measure" -- mesh "$model" --measure best
expect 1 "msh at order 12" -- mesh "$model" --order 12 -o x.msh
expect 1 "no model" -- mesh
expect 1 "unknown command" -- frobnicate
expect 3 "unwritable output" -- mesh "$model" --order 2 -o /nonexistent/dir/out.msh
expect 3 "unwritable json" -- mesh "$model" --order 2 --no-output --json /nonexistent/r.json
expect 2 "quality: missing mesh" -- quality "$model" nosuch.msh
expect 2 "quality: mesh is garbage" -- quality "$model" garbage.step
printf '$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 2 1 2\n2 999 0 2\n1\n2\n0 0 0\n1 1 1\n$EndNodes\n$Elements\n1 1 1 1\n2 999 2 1\n1 1 2 1\n$EndElements\n' > wrongmodel.msh
expect 2 "quality: mesh not on this model" -- quality "$model" wrongmodel.msh
expect 1 "optimize without output" -- optimize "$model" wrongmodel.msh
expect 1 "render without output" -- render wrongmodel.msh
expect 1 "render: bad view" -- render wrongmodel.msh -o x.png --view 0,0,0
expect 1 "render: view not numbers" -- render wrongmodel.msh -o x.png --view up
expect 1 "render: bad size" -- render wrongmodel.msh -o x.png --size 10x10
expect 1 "render: size not WxH" -- render wrongmodel.msh -o x.png --size 800
expect 1 "mesh: bad picture size" -- mesh "$model" --png x.png --png-size 99999x100
expect 2 "render: missing mesh" -- render nosuch.msh -o x.png
expect 2 "render: garbage mesh" -- render garbage.step -o x.png
expect 2 "render: mesh without triangles" -- render empty.step -o x.png
expect 2 "render: mesh not on this model" -- render wrongmodel.msh --model "$model" -o x.png

# a previous output survives a failing run
echo "previous" > keep.msh
"$hocad" mesh nosuch.step --order 2 -o keep.msh >/dev/null 2>&1
if [ "$(cat keep.msh)" = "previous" ]; then pass=$((pass + 1)); else fail=$((fail + 1)); echo "FAIL: previous output clobbered" >&2; fi

# each .msh flavour written by `mesh` is read back by `quality` with the
# same elements and q
"$hocad" mesh "$model" --order 3 -q -o p.msh --msh-parametric --json p.json >/dev/null 2>&1
for flavour in "--msh-version 2.2" "--msh-version 2.2 --msh-binary" "--msh-binary" ""; do
  rm -f f.msh f.json
  "$hocad" mesh "$model" --order 3 -q -o f.msh $flavour >/dev/null 2>&1 &&
    "$hocad" quality "$model" f.msh -q --json f.json >/dev/null 2>&1
  a=$(grep -o '"min": [^,]*, "max": [^,]*, "mean": [^,]*' p.json | tail -1)
  b=$(grep -o '"min": [^,]*, "max": [^,]*, "mean": [^,]*' f.json 2>/dev/null | tail -1)
  n=$(grep -o '"elements": [0-9]*' f.json 2>/dev/null | tail -1)
  if [ -n "$b" ] && [ "$n" = "$(grep -o '"elements": [0-9]*' p.json | tail -1)" ] &&
     awk -v a="$a" -v b="$b" 'BEGIN { split(a, x, /[:,] */); split(b, y, /[:,] */);
       for (i = 2; i <= 6; i += 2) if ((x[i] - y[i])^2 > 1e-20) exit 1 }'; then
    pass=$((pass + 1))
  else
    fail=$((fail + 1)); echo "FAIL: mesh -o with '$flavour' read back by quality: '$b' vs '$a'" >&2
  fi
done
rm -f p.msh p.json f.msh f.json

# help and version
for args in "--help" "mesh --help" "quality --help" "optimize --help" "render --help" "--version"; do
  if $hocad $args >/dev/null 2>&1; then pass=$((pass + 1)); else fail=$((fail + 1)); echo "FAIL: hocad $args" >&2; fi
done

echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
