#!/usr/bin/env bash
# Cost of raising and optimising as the mesh grows, and 1 vs 2 threads.
#
# usage: bench/scaling.sh [HOCAD] [GMSH] [MODEL]
#   MODEL  default examples/models/D150_aircraft_fused.brep
# Linear meshes come from gmsh (default the 5.0 peer; it meshes fast) at
# -clmax H -clmin H/4 for each H in BENCH_SIZES; hocad raises each to order
# BENCH_ORDER (default 3) with `mesh --linear` and optimises it, with each
# thread count in BENCH_THREADS (default "1 2"). One row per run: elements,
# nodes, seconds of elevation / measuring / optimisation, iterations, peak
# RSS, microseconds of optimisation per element, final quality.
# SPDX-License-Identifier: GPL-2.0-or-later
set -u
. "$(dirname "$0")/common.sh"
need_time
use_hocad "${1:-}"
gmsh=$(pick_gmsh "${2:-}")
model=$(readlink -f "${3:-$here/examples/models/D150_aircraft_fused.brep}")
sizes=${BENCH_SIZES:-"1.2 0.4 0.13 0.0906 0.042"}
order=${BENCH_ORDER:-3}
threads_list=${BENCH_THREADS:-"1 2"}

printf "%8s %8s %8s %3s %7s %7s %7s %5s %8s %9s %7s %7s %7s\n" clmax elements nodes thr elev_s meas_s opt_s iters peakMB us/elem minq meanq tangled
for h in $sizes; do
  rm -f "$work"/*
  hmin=$(awk -v h="$h" 'BEGIN{print h/4}')
  "$gmsh" "$model" -2 -clmax "$h" -clmin "$hmin" -nt 1 -o "$work/lin.msh" > "$work/g.log" 2>&1 ||
    { echo "gmsh failed at clmax $h"; continue; }
  for t in $threads_list; do
    rm -f "$work/r.json"
    OMP_NUM_THREADS=$t /usr/bin/time -f "%M" -o "$work/rss" "$hocad" mesh "$model" --linear "$work/lin.msh" \
      --order "$order" --threads "$t" --no-output -q --json "$work/r.json" 2>/dev/null
    [ -s "$work/r.json" ] || { echo "hocad failed at clmax $h, $t threads"; continue; }
    ne=$(jget "$work/r.json" optimized elements)
    meas=$(awk -v a="$(jget "$work/r.json" high-order measure_seconds)" -v b="$(jget "$work/r.json" optimized measure_seconds)" 'BEGIN{print a+b}')
    opt=$(jget "$work/r.json" optimized seconds)
    nodes=$(grep -o '"nodes": [0-9]*' "$work/r.json" | cut -d' ' -f2)
    printf "%8s %8s %8s %3s %7.2f %7.2f %7.2f %5s %8.0f %9.2f %7.4f %7.4f %7s\n" "$h" "$ne" "$nodes" "$t" \
      "$(jget "$work/r.json" high-order seconds)" "$meas" "$opt" "$(jget "$work/r.json" optimized iterations)" \
      "$(rss_mb "$work/rss")" "$(awk -v s="$opt" -v n="$ne" 'BEGIN{print 1e6*s/n}')" \
      "$(jget "$work/r.json" optimized min)" "$(jget "$work/r.json" optimized mean)" \
      "$(jget "$work/r.json" optimized tangled)"
  done
done
