#!/usr/bin/env bash
# hocad and gmsh side by side on the same models, orders and sizes.
#
# usage: bench/compare.sh [HOCAD] [GMSH] [MODELS_DIR]
#   HOCAD  default build/hocad
#   GMSH   default ../shared/peers/gmsh-5.0-dev (gmsh's own route: linear mesh,
#          order elevation, -optimize_ho), falls back to Debian's gmsh
# Cases: BENCH_CASES="model:order:size ..." where size is 0 (each tool's
# default), F (max edge length = bbox diagonal / F for both tools) or hH
# (max edge length H, min H/4 for both: gmsh -clmax H -clmin H/4, hocad
# --size H --size-min H/4). Threads: BENCH_THREADS (default 1).
# Prints one table row per case and tool; every number comes from the run.
# A third row per case ("hocad/g") raises gmsh's own linear mesh of the case
# with hocad (mesh --linear), so elevation times compare on the same mesh:
# its elev_s against gmsh's elev_s (gmsh's "Done meshing order P").
# SPDX-License-Identifier: GPL-2.0-or-later
set -u
. "$(dirname "$0")/common.sh"
need_time
use_hocad "${1:-}"
gmsh=$(pick_gmsh "${2:-}")
models=$(readlink -f "${3:-$here/examples/models}")
threads=${BENCH_THREADS:-1}
cases=${BENCH_CASES:-"gmsh_t20_component8.step:3:0 gear_f360.step:3:0 pulley_at3_t10.step:3:0 D150_aircraft_fused.brep:3:0"}

printf "%-26s %-7s %2s %8s %8s %7s %7s %7s %7s %7s %5s %8s %7s %7s %7s\n" model tool p elements nodes \
  linear_s elev_s meas_s opt_s write_s iters peakMB minq meanq tangled
for c in $cases; do
  IFS=: read -r m p f <<< "$c"
  rm -f "$work"/h.* "$work"/g.* "$work"/g1.* "$work"/hg.*
  model=$models/$m
  diag=$("$hocad" mesh "$model" --order 1 --no-output 2>/dev/null | sed -n 's/.*size \([0-9.e+-]*\) x \([0-9.e+-]*\) x \([0-9.e+-]*\).*/\1 \2 \3/p' |
         awk '{print sqrt($1*$1+$2*$2+$3*$3)}')
  size_args=() gsize_args=()
  if [ "${f#h}" != "$f" ]; then
    h=${f#h}
    hmin=$(awk -v h="$h" 'BEGIN{print h/4}')
    size_args=(--size "$h" --size-min "$hmin")
    gsize_args=(-clmax "$h" -clmin "$hmin")
  elif [ "$f" != 0 ]; then
    h=$(awk -v d="$diag" -v f="$f" 'BEGIN{print d/f}')
    size_args=(--size "$h")
    gsize_args=(-clmax "$h")
  fi
  # hocad
  OMP_NUM_THREADS=$threads /usr/bin/time -f "%M" -o "$work/h.rss" "$hocad" mesh "$model" --order "$p" \
    "${size_args[@]}" --threads "$threads" -q -o "$work/h.msh" --json "$work/h.json" 2>/dev/null
  rc=$?
  if [ -s "$work/h.json" ]; then
    meas=$(awk -v a="$(jget "$work/h.json" linear measure_seconds)" -v b="$(jget "$work/h.json" high-order measure_seconds)" \
               -v c="$(jget "$work/h.json" optimized measure_seconds)" 'BEGIN{print a+b+c}')
    nodes=$(jtop "$work/h.json" nodes)
    printf "%-26s %-7s %2s %8s %8s %7.2f %7.2f %7.2f %7.2f %7.2f %5s %8.0f %7.4f %7.4f %7s\n" "$m" hocad "$p" \
      "$(jget "$work/h.json" optimized elements)" "$nodes" "$(jget "$work/h.json" linear seconds)" \
      "$(jget "$work/h.json" high-order seconds)" "$meas" "$(jget "$work/h.json" optimized seconds)" \
      "$(jtop "$work/h.json" write_seconds)" "$(jget "$work/h.json" optimized iterations)" \
      "$(rss_mb "$work/h.rss")" "$(jget "$work/h.json" optimized min)" \
      "$(jget "$work/h.json" optimized mean)" "$(jget "$work/h.json" optimized tangled)"
  else
    echo "$m hocad p=$p failed (exit $rc)"
  fi
  # gmsh: linear mesh, SetOrder, high-order optimiser, measured by hocad quality
  if [ -n "$gmsh" ]; then
    /usr/bin/time -f "%M" -o "$work/g.rss" "$gmsh" "$model" -2 -order "$p" -optimize_ho -nt "$threads" \
      "${gsize_args[@]}" -o "$work/g.msh" > "$work/g.log" 2>&1
    lin=$(grep -o 'Done meshing 2D (Wall [0-9.e-]*' "$work/g.log" | awk '{print $NF}')
    l1=$(grep -o 'Done meshing 1D (Wall [0-9.e-]*' "$work/g.log" | awk '{print $NF}')
    elev=$(grep -o "Done meshing order $p (Wall [0-9.e-]*" "$work/g.log" | awk '{print $NF}')
    opt=$(grep -o 'Done optimizing mesh (Wall [0-9.e-]*' "$work/g.log" | tail -1 | awk '{print $NF}')
    "$hocad" quality "$model" "$work/g.msh" --json "$work/g.json" -q 2>/dev/null
    if [ -s "$work/g.json" ]; then
      nodes=$(jtop "$work/g.json" nodes)
      printf "%-26s %-7s %2s %8s %8s %7.2f %7.2f %7s %7.2f %7s %5s %8.0f %7.4f %7.4f %7s\n" "$m" gmsh "$p" \
        "$(jget "$work/g.json" input elements)" "$nodes" "$(awk -v a="${l1:-0}" -v b="${lin:-0}" 'BEGIN{print a+b}')" \
        "${elev:-0}" - "${opt:-0}" - - "$(rss_mb "$work/g.rss")" \
        "$(jget "$work/g.json" input min)" "$(jget "$work/g.json" input mean)" "$(jget "$work/g.json" input tangled)"
    else
      echo "$m gmsh p=$p: no readable mesh ($(grep -m1 -i -E 'error' "$work/g.log" | grep -v summary || grep -m1 -i error "$work/g.log"))"
    fi
    # hocad raising gmsh's linear mesh (same options: the same mesh)
    "$gmsh" "$model" -2 -nt "$threads" "${gsize_args[@]}" -o "$work/g1.msh" > "$work/g1.log" 2>&1
    OMP_NUM_THREADS=$threads /usr/bin/time -f "%M" -o "$work/hg.rss" "$hocad" mesh "$model" --order "$p" \
      --linear "$work/g1.msh" --threads "$threads" -q -o "$work/hg.msh" --json "$work/hg.json" 2>/dev/null
    if [ -s "$work/hg.json" ]; then
      nodes=$(jtop "$work/hg.json" nodes)
      printf "%-26s %-7s %2s %8s %8s %7.2f %7.2f %7s %7.2f %7.2f %5s %8.0f %7.4f %7.4f %7s\n" "$m" hocad/g "$p" \
        "$(jget "$work/hg.json" optimized elements)" "$nodes" "$(jget "$work/hg.json" linear seconds)" \
        "$(jget "$work/hg.json" high-order seconds)" - "$(jget "$work/hg.json" optimized seconds)" \
        "$(jtop "$work/hg.json" write_seconds)" "$(jget "$work/hg.json" optimized iterations)" \
        "$(rss_mb "$work/hg.rss")" "$(jget "$work/hg.json" optimized min)" \
        "$(jget "$work/hg.json" optimized mean)" "$(jget "$work/hg.json" optimized tangled)"
    else
      echo "$m hocad on gmsh's linear mesh p=$p failed"
    fi
  fi
done
