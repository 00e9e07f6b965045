#!/usr/bin/env bash
# Order elevation of one linear mesh, hocad against gmsh, runs interleaved so
# that both see the same machine load; medians and their ratio.
#
# usage: bench/elevation.sh [HOCAD] [GMSH] [MODEL]
#   MODEL   default examples/models/D150_aircraft_fused.brep
#   BENCH_CLMAX (default 0.0906: 2.1e5 triangles), BENCH_ORDER (3),
#   BENCH_RUNS (5), BENCH_THREADS (2: both programs get the same cores)
# gmsh meshes the model (-clmax H -clmin H/4) and raises its mesh with
# SetOrder ("Done meshing order P" wall time); hocad raises that same linear
# mesh (mesh --linear, --no-optimize: the "high-order" stage's seconds).
# SPDX-License-Identifier: GPL-2.0-or-later
set -u
. "$(dirname "$0")/common.sh"
use_hocad "${1:-}"
gmsh=$(pick_gmsh "${2:-}")
model=$(readlink -f "${3:-$here/examples/models/D150_aircraft_fused.brep}")
h=${BENCH_CLMAX:-0.0906}
p=${BENCH_ORDER:-3}
runs=${BENCH_RUNS:-5}
t=${BENCH_THREADS:-2}
[ -x "$hocad" ] || { echo "no hocad at $hocad (build it first)"; exit 1; }
[ -n "$gmsh" ] || { echo "no gmsh to compare with"; exit 1; }
hmin=$(awk -v h="$h" 'BEGIN{print h/4}')
"$gmsh" "$model" -2 -clmax "$h" -clmin "$hmin" -nt "$t" -o "$work/lin.msh" > "$work/lin.log" 2>&1 ||
  { echo "gmsh could not mesh $model"; exit 1; }
median() { sort -n | awk '{v[NR]=$1} END{print NR%2 ? v[(NR+1)/2] : (v[NR/2]+v[NR/2+1])/2}'; }
printf "%4s %10s %10s\n" run gmsh_s hocad_s
for r in $(seq "$runs"); do
  "$gmsh" "$model" -2 -clmax "$h" -clmin "$hmin" -order "$p" -nt "$t" -o "$work/g.msh" > "$work/g.log" 2>&1
  g=$(grep -o "Done meshing order $p (Wall [0-9.e-]*" "$work/g.log" | awk '{print $NF}')
  rm -f "$work/h.json"
  OMP_NUM_THREADS=$t "$hocad" mesh "$model" --linear "$work/lin.msh" --order "$p" --threads "$t" \
    --no-optimize --no-output -q --json "$work/h.json" 2>/dev/null
  e=$(grep -o '"name": "high-order"[^}]*' "$work/h.json" | grep -o '"seconds": [0-9.e-]*' | cut -d' ' -f2)
  printf "%4s %10s %10s\n" "$r" "${g:-?}" "${e:-?}"
  echo "$g" >> "$work/g.times"
  echo "$e" >> "$work/h.times"
done
gm=$(median < "$work/g.times")
hm=$(median < "$work/h.times")
echo "elements: $(grep -o '"name": "high-order"[^}]*' "$work/h.json" | grep -o '"elements": [0-9]*' | cut -d' ' -f2), order $p, $t thread(s)"
awk -v g="$gm" -v e="$hm" 'BEGIN{printf "median: gmsh %.3f s, hocad %.3f s: hocad %.1fx faster\n", g, e, g/e}'
