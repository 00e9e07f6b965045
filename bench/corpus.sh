#!/usr/bin/env bash
# Every model of the public corpus against the bounds of issue 32, one
# markdown table row per run of `hocad mesh MODEL --order P`: elements,
# tangled after raising and at the end (the exact test), min and mean q of
# the linear mesh -> the final one, bounds met, wall seconds, the seconds of
# the process start (loading gmsh's and OpenCASCADE's shared libraries,
# the least of three `hocad --version`), the CAD import and gmsh's linear
# meshing, hocad's own seconds per 10^4 elements, peak memory, exit code.
# Orders 2 3 5, and 10 for each model whose order-5 run took under --limit
# seconds. Then the models of hard/ (gmsh itself fails on them): one row
# each, which must be a clean non-zero exit with a message, never a signal
# or a timeout. Last, a summary: runs, bounds met, the failures.
#
# usage: bench/corpus.sh [--orders "2 3 5"] [--limit S] [--threads N]
#                        [--timeout S] [--hocad HOCAD] [--cad-check]
#                        [--mesh-args "ARGS"] [MODELS...]
#   MODELS       model files (paths, or names in the corpus directory; a
#                model in a directory named hard is a hard model). Default:
#                every model in the corpus directory, then every one in its
#                hard/: $HOCAD_CAD, else ../shared/cad beside the repository
#   --orders     default "2 3 5"
#   --limit S    order 10 follows for models whose order-5 run took under S
#                seconds (default 30; 0: no order 10)
#   --threads N  default 2 (OMP_NUM_THREADS and --threads)
#   --timeout S  each run is killed after S seconds, a row of its own
#                (default 1800)
#   --hocad H    default build/hocad
#   --cad-check  also write each mesh and check with `hocad quality` that
#                every node lies on the CAD (within 1e-9 of the model's
#                size); the check is not in the times
#   --mesh-args  more options for each `hocad mesh` run of the tables (split
#                at spaces), e.g. "--size-factor 2"
# Bounds (bench/report_line.py): exit 0, 0 tangled, min q >= 0.9 x linear
# min q (or hocad's notes put every element below that at a CAD cusp or
# across a pinch of its face), mean q >= linear mean q - 0.02, with
# --cad-check every node on the CAD, and at order 3 at most 5 s of hocad's
# own time per 10^4 elements.
# OMP_WAIT_POLICY=passive: on a shared machine spinning OpenMP threads slow
# 2-thread runs a lot.
# SPDX-License-Identifier: GPL-2.0-or-later
set -u
. "$(dirname "$0")/common.sh"
need_time
args=("$@")
orders="2 3 5" limit=30 threads=2 tmo=1800 hocad_arg="" cad_check=0 models=() mesh_args=()
while [ $# -gt 0 ]; do
  case $1 in
    --orders) orders=$2; shift 2 ;;
    --limit) limit=$2; shift 2 ;;
    --threads) threads=$2; shift 2 ;;
    --timeout) tmo=$2; shift 2 ;;
    --hocad) hocad_arg=$2; shift 2 ;;
    --cad-check) cad_check=1; shift ;;
    --mesh-args) read -r -a mesh_args <<< "$2"; shift 2 ;;
    -h|--help) sed -n '2,/^# SPDX/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
    -*) echo "corpus.sh: unknown option $1 (see --help)" >&2; exit 1 ;;
    *) models+=("$1"); shift ;;
  esac
done
use_hocad "$hocad_arg"
py=/usr/bin/python3
line=$here/bench/report_line.py
cad=$(readlink -f "${HOCAD_CAD:-$here/../shared/cad}")
if [ ${#models[@]} -eq 0 ]; then
  [ -d "$cad" ] || { echo "corpus.sh: no corpus at $cad (set HOCAD_CAD)" >&2; exit 1; }
  for f in "$cad"/*.* "$cad"/hard/*.*; do
    case ${f,,} in *.step|*.stp|*.iges|*.igs|*.brep) models+=("$f") ;; esac
  done
fi
normal=() hard=()
for m in "${models[@]}"; do
  [ -f "$m" ] || m=$cad/$m
  [ -f "$m" ] || { echo "corpus.sh: no model $m" >&2; exit 1; }
  m=$(readlink -f "$m")
  case $m in */hard/*) hard+=("$m") ;; *) normal+=("$m") ;; esac
done

export OMP_WAIT_POLICY=passive OMP_NUM_THREADS=$threads
runs=0 met=0 failures=()

# label MODEL: its name in the tables, relative to the corpus directory
# (hard/x.igs), else the file name
label() {
  case $1 in "$cad"/*) echo "${1#"$cad"/}" ;; *) basename "$1" ;; esac
}

# one_run MODEL ORDER: a row; sets $wall (seconds) of the run
one_run() {
  local m=$1 p=$2 name rc out=() cadf=()
  name=$(label "$m")
  rm -f "$work"/r.json "$work"/m.msh "$work"/q.txt "$work"/why
  [ $cad_check = 1 ] && out=(-o "$work/m.msh") || out=(--no-output)
  /usr/bin/time -f "%e %M" -o "$work/time" timeout -k 10 "$tmo" "$hocad" mesh "$m" --order "$p" \
    --threads "$threads" "${out[@]}" "${mesh_args[@]}" -q --json "$work/r.json" \
    > /dev/null 2> "$work/err"
  rc=$?
  wall=$(tail -n 1 "$work/time" | cut -d' ' -f1)
  if [ $cad_check = 1 ] && [ -s "$work/m.msh" ]; then
    "$hocad" quality "$m" "$work/m.msh" --threads "$threads" > "$work/q.txt" 2>&1
    cadf=(--cad "$work/q.txt")
  fi
  runs=$((runs + 1))
  if "$py" "$line" run --model "$name" --order "$p" --exit "$rc" --wall "$wall" \
    --rss-kb "$(tail -n 1 "$work/time" | cut -d' ' -f2)" --json "$work/r.json" \
    --stderr "$work/err" --timeout "$tmo" --why "$work/why" --startup "$startup" "${cadf[@]}"; then
    met=$((met + 1))
  else
    failures+=("$name p$p: $(cat "$work/why" 2>/dev/null)")
  fi
}

# the process start: `hocad --version` only loads the shared libraries
startup=$(for i in 1 2 3; do
  /usr/bin/time -f %e "$hocad" --version 2>&1 > /dev/null | tail -n 1
done | sort -n | head -n 1)
[ -n "$startup" ] || startup=0
bench_header "${args[@]}"
echo "Process start (loading gmsh's and OpenCASCADE's libraries): $startup s, in \`CAD + linear s\`."
echo
if [ ${#normal[@]} -gt 0 ]; then
  "$py" "$line" header
  for m in "${normal[@]}"; do
    ten=0
    for p in $orders; do
      one_run "$m" "$p"
      [ "$p" = 5 ] && awk -v w="$wall" -v l="$limit" 'BEGIN { exit !(w < l) }' && ten=1
    done
    case " $orders " in *" 10 "*) ten=0 ;; esac
    [ $ten = 1 ] && one_run "$m" 10
  done
  echo
fi
if [ ${#hard[@]} -gt 0 ]; then
  "$py" "$line" hard-header
  for m in "${hard[@]}"; do
    name=$(label "$m")
    rm -f "$work"/why
    timeout -k 10 "$tmo" "$hocad" mesh "$m" --order 3 --threads "$threads" --no-output -q \
      > /dev/null 2> "$work/err"
    rc=$?
    runs=$((runs + 1))
    if "$py" "$line" hard --model "$name" --exit "$rc" --stderr "$work/err" --timeout "$tmo" \
      --why "$work/why"; then
      met=$((met + 1))
    else
      failures+=("$name: $(cat "$work/why" 2>/dev/null)")
    fi
  done
  echo
fi
echo "Summary: $runs runs, $met met the bounds (hard/: a clean refusal), ${#failures[@]} did not${failures[*]:+:}"
for f in "${failures[@]}"; do echo "- $f"; done
