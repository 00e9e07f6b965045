#!/usr/bin/env bash
# hocad optimize on gmsh's own high-order meshes: `gmsh MODEL -2 -order P`
# (no -optimize_ho: gmsh's optimiser does nothing to surface elements),
# then `hocad optimize MODEL gmsh.msh`. Per model: elements in -> out
# (more where tangled elements were split), tangled in gmsh's mesh ->
# after, min and mean q before -> after, iterations and seconds of the
# kept optimisation, splits, wall time of the whole command, peak memory.
#
# usage: bench/gmsh_optimize.sh [HOCAD] [GMSH] [MODELS_DIR]
#   GMSH          default ../shared/peers/gmsh-5.0-dev, else `gmsh`; `lib`:
#                 Debian's libgmsh (4.8) through the tests' helper
#                 build/tests/gmsh_ho_mesh (the same as `gmsh -2 -order P`)
#   BENCH_MODELS  model file names (default: every model in MODELS_DIR)
#   BENCH_ORDER   default 3;  BENCH_THREADS default 2
# SPDX-License-Identifier: GPL-2.0-or-later
set -u
. "$(dirname "$0")/common.sh"
need_time
use_hocad "${1:-}"
if [ "${2:-}" = lib ]; then
  gmsh=$here/build/tests/gmsh_ho_mesh
else
  gmsh=$(pick_gmsh "${2:-}")
fi
[ -n "$gmsh" ] || { echo "no gmsh found"; exit 1; }
models=$(readlink -f "${3:-$here/examples/models}")
list=${BENCH_MODELS:-$(cd "$models" && ls *.step *.stp *.brep *.iges *.igs 2>/dev/null)}
order=${BENCH_ORDER:-3}
threads=${BENCH_THREADS:-2}

printf "%-26s %2s %11s %9s %15s %15s %5s %8s %5s %7s %7s\n" model p elements tangled \
  "min q in->opt" "mean q in->opt" iters opt_s split wall_s peakMB
for m in $list; do
  rm -f "$work"/*
  if [ "${2:-}" = lib ]; then
    "$gmsh" "$models/$m" "$order" "$work/g.msh" > "$work/g.log" 2>&1
  else
    "$gmsh" "$models/$m" -2 -order "$order" -nt 1 -o "$work/g.msh" > "$work/g.log" 2>&1
  fi
  if [ $? -ne 0 ] || [ ! -s "$work/g.msh" ]; then
    echo "$m: gmsh made no mesh ($(grep -m1 -i error "$work/g.log"))"
    continue
  fi
  OMP_NUM_THREADS=$threads /usr/bin/time -f "%e %M" -o "$work/rss" "$hocad" optimize "$models/$m" "$work/g.msh" \
    -o "$work/o.msh" --threads "$threads" -q --json "$work/r.json" > /dev/null 2> "$work/h.err"
  rc=$?
  if [ ! -s "$work/r.json" ]; then
    echo "$m: hocad optimize failed (exit $rc: $(head -c 200 "$work/h.err"))"
    continue
  fi
  printf "%-26s %2s %5s->%-5s %4s->%-4s %7.4f->%.4f %7.4f->%.4f %5s %8.2f %5s %7.2f %7.0f\n" \
    "$m" "$order" "$(jget "$work/r.json" input elements)" "$(jget "$work/r.json" optimized elements)" \
    "$(jget "$work/r.json" input tangled)" \
    "$(jget "$work/r.json" optimized tangled)" "$(jget "$work/r.json" input min)" \
    "$(jget "$work/r.json" optimized min)" "$(jget "$work/r.json" input mean)" \
    "$(jget "$work/r.json" optimized mean)" "$(jget "$work/r.json" optimized iterations)" \
    "$(jget "$work/r.json" optimized seconds)" "$(jtop "$work/r.json" refinements)" \
    "$(tail -n 1 "$work/rss" | cut -d' ' -f1)" "$(tail -n 1 "$work/rss" | awk '{print $2 / 1024}')"
done
