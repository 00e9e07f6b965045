#!/usr/bin/env bash
# Cost of one optimiser sweep per element against the order p, on one model,
# one thread (issue 33: it must grow no faster than p^4), and the log-log
# slope of that cost against p (least squares).
#
# usage: bench/orders_cost.sh [--orders "2 3 4 5 6 8 10"] [--sweeps N]
#                             [--hocad HOCAD] [--timeout S] MODEL
#   --sweeps N   --max-iterations of each run (default 5): the first sweeps,
#                in which nearly every free node moves; 0: hocad's default,
#                sweeps to convergence, where later sweeps move few nodes
#   --timeout S  each run killed after S seconds (default 3600)
# Each run: `hocad mesh MODEL --order P --threads 1 --refinements 0
# --max-iterations N --no-output --json R.json` (no remeshing or splits:
# one linear mesh for every p). From the JSON's first "optimized" stage:
# its elements, its sweeps (`iterations`, every phase and attempt counted)
# and its seconds (the optimiser's call: sweeps, the tangle tests between
# them and the final polish). s/sweep/el = seconds / sweeps / elements.
# Sweeps do not all cost the same: a node whose move stalls sleeps, so the
# JSON's figures undercount a full sweep when most nodes sleep; hence the
# default cap. Where util-linux's `script` is there, the run also goes
# through a pseudo terminal so hocad prints its per-sweep events ("N nodes
# moved"); their sum over the first optimisation is the node moves column
# (moves, not visits: a node tried and left where it was is not counted).
# SPDX-License-Identifier: GPL-2.0-or-later
set -u
. "$(dirname "$0")/common.sh"
args=("$@")
orders="2 3 4 5 6 8 10" sweeps=5 hocad_arg="" tmo=3600 model=""
while [ $# -gt 0 ]; do
  case $1 in
    --orders) orders=$2; shift 2 ;;
    --sweeps) sweeps=$2; shift 2 ;;
    --hocad) hocad_arg=$2; shift 2 ;;
    --timeout) tmo=$2; shift 2 ;;
    -h|--help) sed -n '2,/^# SPDX/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
    -*) echo "orders_cost.sh: unknown option $1 (see --help)" >&2; exit 1 ;;
    *) [ -z "$model" ] || { echo "orders_cost.sh: one model only" >&2; exit 1; }
       model=$1; shift ;;
  esac
done
[ -n "$model" ] || { echo "usage: bench/orders_cost.sh [options] MODEL (see --help)" >&2; exit 1; }
[ -f "$model" ] || { echo "orders_cost.sh: no model $model" >&2; exit 1; }
use_hocad "$hocad_arg"
export OMP_WAIT_POLICY=passive OMP_NUM_THREADS=1
have_script=0
command -v script > /dev/null && have_script=1
iters=()
[ "$sweeps" -gt 0 ] && iters=(--max-iterations "$sweeps")

bench_header "${args[@]}"
echo "| p | elements | sweeps | optimise s | ms / sweep / element | node moves | tangled left |"
echo "|---|---|---|---|---|---|---|"
: > "$work/points"
for p in $orders; do
  rm -f "$work/r.json"
  cmd=("$hocad" mesh "$model" --order "$p" --threads 1 --refinements 0 "${iters[@]}" --no-output
       --json "$work/r.json")
  if [ $have_script = 1 ]; then
    # a pseudo terminal: hocad prints its sweeps there; their lines kept
    timeout -k 10 "$tmo" script -qec "$(printf '%q ' "${cmd[@]}")" /dev/null < /dev/null \
      | tr -d '\r' > "$work/out"
  else
    timeout -k 10 "$tmo" "${cmd[@]}" > "$work/out" 2>&1
  fi
  if [ ! -s "$work/r.json" ]; then
    echo "| $p | - | - | - | - | - | - | no report ($(grep -m1 -a 'error' "$work/out" | tr -d '|')) |"
    continue
  fi
  read -r ne it sec tang _ _ < <(/usr/bin/python3 "$here/bench/report_line.py" sweep --json "$work/r.json")
  # node moves of the first optimisation: the sweep lines up to the first
  # stage line after "optimizing" (a later "smoothed" stage has its own)
  moves=$(awk '/\[hocad\] optimizing/ { on++ } on == 1 && /\[hocad\] iteration/ {
    for (i = 1; i <= NF; ++i) if ($i == "nodes" && $(i + 1) == "moved") s += $(i - 1) }
    END { print s + 0 }' "$work/out")
  awk -v p="$p" -v ne="$ne" -v it="$it" -v s="$sec" -v mv="$moves" -v t="$tang" \
    -v ev="$have_script" 'BEGIN {
    per = it > 0 ? s / it / ne : 0
    m = ev ? mv : "-"
    printf "| %d | %d | %d | %.3f | %.4f | %s | %d |\n", p, ne, it, s, 1e3 * per, m, t }'
  echo "$p $ne $it $sec $moves" >> "$work/points"
done
echo
# least squares slope of log(seconds per sweep per element) against log(p)
awk '
  function fit(   i, sx, sy, sxx, sxy, n, x, y) {
    n = 0; sx = sy = sxx = sxy = 0
    for (i = 1; i <= N; ++i) {
      y = val[i]; if (!(y > 0)) continue
      x = log(P[i]); y = log(y); ++n; sx += x; sy += y; sxx += x * x; sxy += x * y
    }
    if (n < 2 || n * sxx == sx * sx) return "-"
    return sprintf("%.2f", (n * sxy - sx * sy) / (n * sxx - sx * sx))
  }
  $3 > 0 { ++N; P[N] = $1; val[N] = $4 / $3 / $2; ps = ps " " $1 }
  END { printf "Log-log slope (least squares over p =%s): seconds per sweep per element ~ p^%s.\n", ps, fit() }
  ' "$work/points"
