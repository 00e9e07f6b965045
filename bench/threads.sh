#!/usr/bin/env bash
# The optimiser on 1 and on 2 threads, interleaved, with medians: the
# machine is shared and one run varies by 15% or more.
#
# usage: bench/threads.sh [HOCAD] [GMSH] [MODEL]
#   MODEL  default examples/models/D150_aircraft_fused.brep
# The linear mesh comes from gmsh (default the 5.0 peer) at -clmax H
# -clmin H/4, H = BENCH_SIZE (default 0.0906: 2.1e5 triangles of the
# aircraft); hocad raises it to BENCH_ORDER (default 3) and optimises it
# BENCH_RUNS times (default 7) with each thread count in turn. Prints every
# run's optimisation seconds, the medians, their ratio and the median of
# the ratios of the pairs.
# SPDX-License-Identifier: GPL-2.0-or-later
set -u
. "$(dirname "$0")/common.sh"
use_hocad "${1:-}"
gmsh=$(pick_gmsh "${2:-}")
model=$(readlink -f "${3:-$here/examples/models/D150_aircraft_fused.brep}")
h=${BENCH_SIZE:-0.0906}
order=${BENCH_ORDER:-3}
runs=${BENCH_RUNS:-7}
hmin=$(awk -v h="$h" 'BEGIN{print h/4}')
"$gmsh" "$model" -2 -clmax "$h" -clmin "$hmin" -nt 1 -o "$work/lin.msh" > "$work/g.log" 2>&1 ||
  { echo "gmsh failed at clmax $h"; exit 1; }
seconds() { grep -o '"name": "optimized"[^}]*' "$1" | grep -o '"seconds": [0-9.]*' | cut -d' ' -f2; }
median() { sort -g | awk '{v[NR] = $1} END {print NR % 2 ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2}'; }
: > "$work/t1"; : > "$work/t2"; : > "$work/ratio"
printf "%4s %8s %8s %6s\n" run "1 thr" "2 thr" ratio
for i in $(seq "$runs"); do
  for t in 1 2; do
    rm -f "$work/r.json"
    OMP_NUM_THREADS=$t "$hocad" mesh "$model" --linear "$work/lin.msh" --order "$order" --threads "$t" \
      --no-output -q --json "$work/r.json" > /dev/null 2>&1
    [ -s "$work/r.json" ] || { echo "hocad failed ($t threads)"; exit 1; }
    seconds "$work/r.json" > "$work/s$t"
  done
  a=$(cat "$work/s1") b=$(cat "$work/s2")
  echo "$a" >> "$work/t1"; echo "$b" >> "$work/t2"
  awk -v a="$a" -v b="$b" 'BEGIN{print a / b}' >> "$work/ratio"
  printf "%4d %8.2f %8.2f %6.2f\n" "$i" "$a" "$b" "$(tail -1 "$work/ratio")"
done
m1=$(median < "$work/t1") m2=$(median < "$work/t2") mr=$(median < "$work/ratio")
elements=$(grep -o '"name": "optimized"[^}]*' "$work/r.json" | grep -o '"elements": [0-9]*' | cut -d' ' -f2)
printf "%s elements, order %s: median 1 thread %.2f s, 2 threads %.2f s: %.2fx (median of the pairs' ratios %.2fx)\n" \
  "$elements" "$order" "$m1" "$m2" "$(awk -v a="$m1" -v b="$m2" 'BEGIN{print a / b}')" "$mr"
