#!/usr/bin/env bash
# gmsh 5.0's strongest surface route beside hocad on one model and order
# (issue 33): gmsh meshes the model with its volumes deleted and runs its
# high-order optimiser on the surface (Mesh.HighOrderOptimize = 2, elastic
# then optimisation, nodes moved in (u, v); ../shared/peers/README.md), and
# `hocad mesh` meshes the same model. Both results are then measured by the
# same `hocad quality MODEL MESH.msh` (the paper's Definition 2, tangled by
# the exact test). One markdown row each: tool, wall seconds, peak MB,
# elements, tangled, min q, mean q, exit code.
#
# usage: bench/gmsh_side_by_side.sh [--threads N] [--sizes hocad|gmsh]
#                                   [--hocad HOCAD] [--gmsh GMSH] [--timeout S] MODEL ORDER
#   --threads N  both tools (gmsh -nt N, hocad --threads N), default 2
#   --sizes      hocad (default): gmsh gets hocad's default linear sizes
#                (Mesh.MeshSizeMax = diagonal / 20, MeshSizeMin = that / 10,
#                MeshSizeFromCurvature = 8; the diagonal as hocad prints the
#                model's size), so both start from like meshes; gmsh: gmsh's
#                own defaults
#   --gmsh G     default ../shared/peers/gmsh-5.0-dev, else `gmsh` on the PATH
#   --timeout S  each tool killed after S seconds (default 3600)
# The .geo gmsh runs is printed under the table. hocad keeps its defaults
# (its refinements and remeshing included: its row is what a user gets).
# SPDX-License-Identifier: GPL-2.0-or-later
set -u
. "$(dirname "$0")/common.sh"
need_time
args=("$@")
threads=2 sizes=hocad hocad_arg="" gmsh_arg="" tmo=3600 pos=()
while [ $# -gt 0 ]; do
  case $1 in
    --threads) threads=$2; shift 2 ;;
    --sizes) sizes=$2; shift 2 ;;
    --hocad) hocad_arg=$2; shift 2 ;;
    --gmsh) gmsh_arg=$2; shift 2 ;;
    --timeout) tmo=$2; shift 2 ;;
    -h|--help) sed -n '2,/^# SPDX/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
    -*) echo "gmsh_side_by_side.sh: unknown option $1 (see --help)" >&2; exit 1 ;;
    *) pos+=("$1"); shift ;;
  esac
done
if [ ${#pos[@]} -ne 2 ]; then
  echo "usage: bench/gmsh_side_by_side.sh [options] MODEL ORDER (see --help)" >&2
  exit 1
fi
model=$(readlink -f "${pos[0]}") order=${pos[1]}
[ -f "$model" ] || { echo "gmsh_side_by_side.sh: no model ${pos[0]}" >&2; exit 1; }
case $order in [1-9]|10) ;; *) echo "gmsh_side_by_side.sh: order 1..10 (gmsh's MSH limit)" >&2; exit 1 ;; esac
case $sizes in hocad|gmsh) ;; *) echo "gmsh_side_by_side.sh: --sizes hocad or gmsh" >&2; exit 1 ;; esac
case $model in *'"'*) echo "gmsh_side_by_side.sh: a model path with a double quote" >&2; exit 1 ;; esac
use_hocad "$hocad_arg"
gmsh=$(pick_gmsh "$gmsh_arg")
[ -n "$gmsh" ] && [ -x "$gmsh" ] || { echo "gmsh_side_by_side.sh: no gmsh found" >&2; exit 1; }
export OMP_WAIT_POLICY=passive OMP_NUM_THREADS=$threads

bench_header "${args[@]}"

# row TOOL TIMEFILE EXIT MESH: measure MESH with hocad quality, print the row
row() {
  local tool=$1 tf=$2 rc=$3 msh=$4 wall mb
  wall=$(tail -n 1 "$tf" | cut -d' ' -f1) mb=$(tail -n 1 "$tf" | awk '{ printf "%.0f", $2 / 1024 }')
  rm -f "$work/q.json"
  if [ -s "$msh" ]; then
    "$hocad" quality "$model" "$msh" --threads "$threads" -q --json "$work/q.json" \
      > /dev/null 2> "$work/q.err"
  fi
  if [ ! -s "$work/q.json" ]; then
    local why="no mesh"
    [ -s "$msh" ] && why="hocad quality: $(grep -m1 -a error "$work/q.err" | sed 's/^hocad: error: //' | tr -d '|')"
    echo "| $tool | $wall | $mb | - | - | - | - | $rc ($why) |"
    return
  fi
  printf '| %s | %s | %s | %s | %s | %.4f | %.4f | %s |\n' "$tool" "$wall" "$mb" \
    "$(jget "$work/q.json" input elements)" "$(jget "$work/q.json" input tangled)" \
    "$(jget "$work/q.json" input min)" "$(jget "$work/q.json" input mean)" "$rc"
}

# hocad first: its model line gives the diagonal gmsh's sizes follow
/usr/bin/time -f "%e %M" -o "$work/h.time" timeout -k 10 "$tmo" "$hocad" mesh "$model" \
  --order "$order" --threads "$threads" -o "$work/h.msh" > "$work/h.out" 2> "$work/h.err"
h_rc=$?
size_lines=""
if [ "$sizes" = hocad ]; then
  diag=$(grep -m1 -o 'size [-0-9.e+]* x [-0-9.e+]* x [-0-9.e+]*' "$work/h.out" |
    awk '{ printf "%.17g", sqrt($2 * $2 + $4 * $4 + $6 * $6) }')
  if [ -z "$diag" ]; then
    echo "gmsh_side_by_side.sh: hocad printed no model size: $(head -c 300 "$work/h.err")" >&2
    exit 1
  fi
  size_lines="Mesh.MeshSizeMax = $diag / 20;
Mesh.MeshSizeMin = $diag / 200;
Mesh.MeshSizeFromCurvature = 8;"
fi
cat > "$work/route.geo" <<EOF
SetFactory("OpenCASCADE");
v() = ShapeFromFile("$model");
Delete { Volume{:}; }
${size_lines:+$size_lines
}Mesh.ElementOrder = $order;
Mesh.HighOrderOptimize = 2;
EOF
/usr/bin/time -f "%e %M" -o "$work/g.time" timeout -k 10 "$tmo" "$gmsh" "$work/route.geo" -2 \
  -nt "$threads" -o "$work/g.msh" > "$work/g.log" 2>&1
g_rc=$?

echo "| tool | wall s | peak MB | elements | tangled | min q | mean q | exit |"
echo "|---|---|---|---|---|---|---|---|"
row "gmsh $("$gmsh" --version 2>&1 | head -n 1), HighOrderOptimize 2" "$work/g.time" "$g_rc" "$work/g.msh"
row "hocad mesh" "$work/h.time" "$h_rc" "$work/h.msh"
echo
echo "gmsh ran (\`$(basename "$gmsh") route.geo -2 -nt $threads -o g.msh\`):"
echo
echo '```'
cat "$work/route.geo"
echo '```'
msgs=$(grep -a -i 'error\|fail' "$work/g.log" | sort | uniq -c | sort -rn | head -n 3)
[ -n "$msgs" ] && printf '\ngmsh said (most frequent error/failure lines):\n\n```\n%s\n```\n' "$msgs"
herr=$(grep -a -v '^$' "$work/h.err" | head -n 3)
[ -n "$herr" ] && printf '\nhocad said:\n\n```\n%s\n```\n' "$herr"
exit 0
