#!/usr/bin/env bash
# The optimiser against issue 3's bounds, per model and order: tangled
# elements, min and mean q of the linear mesh and of the optimised one,
# iterations, seconds and peak memory of the run.
#
# usage: bench/orders.sh [HOCAD] [MODELS_DIR]
#   BENCH_MODELS  model file names (default: every model in MODELS_DIR,
#                 default examples/models)
#   BENCH_ORDERS  default "2 3 5"
#   BENCH_THREADS default 2
# Each run is `hocad mesh MODEL --order P --no-output` at hocad's default
# sizes. Columns: iterations and seconds of the last optimisation, ref the
# refinements made (the JSON's `refinements`: splits, tried or kept, and
# remeshings of faces, each of those a whole new run), wall_s the
# whole run; bounds checks 0 tangled, min q >= 0.9 x linear min q and mean
# q >= linear mean q - 0.02 ("ok", or what failed), against the linear mesh
# of the last attempt.
# SPDX-License-Identifier: GPL-2.0-or-later
set -u
. "$(dirname "$0")/common.sh"
need_time
use_hocad "${1:-}"
models=$(readlink -f "${2:-$here/examples/models}")
list=${BENCH_MODELS:-$(cd "$models" && ls *.step *.stp *.brep *.iges *.igs 2>/dev/null)}
orders=${BENCH_ORDERS:-"2 3 5"}
threads=${BENCH_THREADS:-2}

printf "%-26s %2s %8s %9s %15s %15s %5s %8s %3s %8s %7s  %s\n" model p elements tangled \
  "min q lin->opt" "mean q lin->opt" iters opt_s ref wall_s peakMB bounds
for m in $list; do
  for p in $orders; do
    rm -f "$work/r.json"
    start=$(date +%s.%N)
    OMP_NUM_THREADS=$threads /usr/bin/time -f "%M" -o "$work/rss" "$hocad" mesh "$models/$m" --order "$p" \
      --threads "$threads" --no-output -q --json "$work/r.json" > /dev/null 2>&1
    rc=$?
    wall=$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }')
    if [ ! -s "$work/r.json" ]; then
      echo "$m p=$p: hocad failed (exit $rc)"
      continue
    fi
    # the final stage: "smoothed" if hocad made one (elements below the
    # bound optimised once more), else "optimized"
    fin=optimized
    grep -q '"name": "smoothed"' "$work/r.json" && fin=smoothed
    ne=$(jget "$work/r.json" $fin elements)
    t0=$(jget "$work/r.json" high-order tangled) t1=$(jget "$work/r.json" $fin tangled)
    l_min=$(jget "$work/r.json" linear min) o_min=$(jget "$work/r.json" $fin min)
    l_mean=$(jget "$work/r.json" linear mean) o_mean=$(jget "$work/r.json" $fin mean)
    verdict=$(awk -v t="$t1" -v lm="$l_min" -v om="$o_min" -v la="$l_mean" -v oa="$o_mean" 'BEGIN {
      v = ""; if (t > 0) v = v t " tangled; ";
      if (om < 0.9 * lm) v = v "min q below 0.9 x linear; ";
      if (oa < la - 0.02) v = v "mean q below linear - 0.02; ";
      print v == "" ? "ok" : v }')
    printf "%-26s %2s %8s %4s->%-4s %7.4f->%.4f %7.4f->%.4f %5s %8.2f %3s %8s %7.0f  %s\n" "$m" "$p" \
      "$ne" "$t0" "$t1" "$l_min" "$o_min" "$l_mean" "$o_mean" \
      "$(jget "$work/r.json" optimized iterations)" "$(jget "$work/r.json" optimized seconds)" \
      "$(jtop "$work/r.json" refinements)" "$wall" "$(rss_mb "$work/rss")" "$verdict"
  done
done
