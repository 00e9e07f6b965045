#!/usr/bin/env bash
# hocad mesh / quality / optimize on bundled models: the report, the JSON,
# files gmsh can read, and the round trip through hocad quality.
# usage: cli_mesh.sh HOCAD SOURCE_DIR
set -u
hocad=$(readlink -f "$1")
src=$(readlink -f "$2")
pass=0
fail=0
build=$(pwd) # ctest runs this from the tests' build directory
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
ok() { if eval "$2"; then pass=$((pass + 1)); else fail=$((fail + 1)); echo "FAIL: $1" >&2; fi; }

model=$src/examples/models/gmsh_t20_component8.step
"$hocad" mesh "$model" --order 3 -o t20.msh --vtu t20.vtu --json t20.json > out.txt 2> err.txt
code=$?
ok "mesh exits 0" "[ $code -eq 0 ]"
ok "report has three stages" "grep -q '^linear ' out.txt && grep -q '^high-order ' out.txt && grep -q '^optimized ' out.txt"
ok "json stages" "grep -q '\"stages\"' t20.json && [ \$(grep -c '\"name\"' t20.json) -eq 3 ]"
ok "optimized stage untangled" "grep -q '\"name\": \"optimized\".*\"tangled\": 0,' t20.json"
ok "msh written" "head -2 t20.msh | grep -q '^4.1 0 8'"
ok "vtu written" "head -c 200 t20.vtu | grep -q UnstructuredGrid"
# measured back from the file: the same numbers
"$hocad" quality "$model" t20.msh --json q.json > qout.txt 2>&1
ok "quality exits 0" "[ $? -eq 0 ]"
mean_mesh=$(grep -o '"name": "optimized".*"mean": [0-9.e-]*' t20.json | grep -o '"mean": [0-9.e-]*' | cut -d' ' -f2)
mean_file=$(grep -o '"mean": [0-9.e-]*' q.json | cut -d' ' -f2)
ok "file measures as the run did ($mean_mesh vs $mean_file)" "awk -v a=$mean_mesh -v b=$mean_file 'BEGIN{d=a-b; if(d<0)d=-d; exit !(d<1e-9)}'"
# --size-factor scales the default sizes: 1 is the default mesh, 2 one
# with edges up to twice as long (a third of the triangles on this part)
linear_elements() {
  rm -f lin.json # (exit 5: the raised mesh is left tangled)
  "$hocad" mesh "$model" --order 2 --no-optimize --no-output --json lin.json "$@" > lin.txt 2>&1
  grep -o '"name": "linear"[^}]*' lin.json | grep -o '"elements": [0-9]*' |
    cut -d' ' -f2
}
n_default=$(linear_elements)
n_one=$(linear_elements --size-factor 1)
n_two=$(linear_elements --size-factor 2)
ok "size factor: 1 ($n_one) is the default ($n_default), 2 ($n_two) coarser" \
  "[ -n '$n_default' ] && [ '$n_one' = '$n_default' ] && [ '${n_two:-0}' -gt 0 ] && [ '${n_two:-0}' -lt \$(( ${n_default:-0} / 2 )) ]"
# a thin disk (rim 0.04 wide, edges 0.707): graded down to its rim, edges
# swapped, and said so; --no-grading keeps gmsh's 872 triangles, without
# the notes
disk=$src/tests/data/thin_disk.brep
"$hocad" mesh "$disk" --order 1 --no-output --json dg.json > /dev/null 2> dg.txt
"$hocad" mesh "$disk" --order 1 --no-grading --no-output --json dn.json > /dev/null 2> dn.txt
n_dg=$(grep -o '"name": "linear"[^}]*' dg.json | grep -o '"elements": [0-9]*' | cut -d' ' -f2)
n_dn=$(grep -o '"name": "linear"[^}]*' dn.json | grep -o '"elements": [0-9]*' | cut -d' ' -f2)
ok "thin disk graded ($n_dg), --no-grading gmsh's mesh ($n_dn)" \
  "[ '${n_dn:-0}' = 872 ] && [ '${n_dg:-0}' -gt 872 ] && grep -q 'and 1 face(s) narrower' dg.txt && ! grep -q 'graded down' dn.txt"
ok "thin disk: edges swapped, none with --no-grading" \
  "grep -q 'edge(s) of the linear mesh swapped' dg.txt && ! grep -q 'swapped' dn.txt"

# optimize a mesh read from a file (here the raised, unoptimized one; at
# order 2 it has 4 tangled elements)
"$hocad" mesh "$model" --order 2 --no-optimize -o raised.msh > /dev/null 2>&1
"$hocad" optimize "$model" raised.msh -o fixed.msh --json fix.json > /dev/null 2>&1
ok "optimize exits 0" "[ $? -eq 0 ]"
ok "optimize untangles" "grep -q '\"name\": \"optimized\".*\"tangled\": 0,' fix.json"
# a tangled input is re-placed from its corners; hocad's own raised mesh
# comes back with the same tangled elements (the same placement)
t_in=$(grep -o '"name": "input"[^}]*' fix.json | grep -o '"tangled": [0-9]*' | cut -d' ' -f2)
t_re=$(grep -o '"name": "re-placed"[^}]*' fix.json | grep -o '"tangled": [0-9]*' | cut -d' ' -f2)
ok "re-placed stage, as tangled as the input ($t_in, ${t_re:-none})" "[ -n '$t_re' ] && [ '$t_in' -gt 0 ] && [ '$t_re' = '$t_in' ]"
"$hocad" optimize "$model" raised.msh -o kept.msh --keep-nodes --json kept.json > /dev/null 2>&1
ok "--keep-nodes: no re-placed stage, untangled" "! grep -q re-placed kept.json && grep -q '\"name\": \"optimized\".*\"tangled\": 0,' kept.json"
# order above 10: VTU only
"$hocad" mesh "$src/examples/models/screw.step" --order 12 --no-optimize --vtu s12.vtu --no-output > /dev/null 2>&1
ok "order 12 to vtu" "[ $? -eq 0 ] && [ -s s12.vtu ]"
# stopped by --max-iterations with tangled elements left: exit 5 and the
# limit named as the reason (order 3 of the bottle keeps tangled elements
# after 1 sweep and the second attempt's 1). The repair cases on the bottle
# take gmsh's mesh as it is (--no-grading): the graded mesh, with the
# bottle's thin faces resolved, leaves fewer elements to repair.
bottle=$src/examples/models/occt_bottle.brep
"$hocad" mesh "$bottle" --order 3 --max-iterations 1 --refinements 0 --no-grading --no-output -q \
  --json lim.json \
  > /dev/null 2> lim.txt
code=$?
ok "tangled at the iteration limit exits 5" "[ $code -eq 5 ]"
ok "the limit is named" "grep -q 'still tangled after 2 iteration(s) (the limit, with a second attempt: raise --max-iterations)' lim.txt"
ok "no cusp note before convergence" "! grep -q 'cusp' lim.txt"
ok "second attempt in the json" "grep -q '\"second_attempt\": 2,' lim.json && grep -q '\"refinements\": 0,' lim.json"
# tangled elements left: split first (kept only if that leaves none
# tangled), else their faces meshed again finer, at most twice
"$hocad" mesh "$bottle" --order 3 --max-iterations 1 --no-grading --no-output --json ref.json \
  > ref.txt 2> referr.txt
n_ref=$(grep -o '"refinements": [0-9]*' ref.json | cut -d' ' -f2)
n_rem=$(grep -o '"remeshings": [0-9]*' ref.json | cut -d' ' -f2)
n_msg=$(( $(grep -c 'meshing their faces again' referr.txt) + $(grep -c 'splitting them' referr.txt) ))
ok "refinements said and counted (${n_ref:-none}, ${n_rem:-none} remeshings)" "[ -n '$n_rem' ] && [ '$n_rem' -ge 1 ] && [ '$n_rem' -le 2 ] && [ \$(grep -c 'meshing their faces again' referr.txt) -eq '$n_rem' ] && [ '$n_ref' = '$n_msg' ]"
ok "splits tried before remeshing" "grep -q 'splitting the tangled elements first' referr.txt && grep -q 'meshing the faces again instead' referr.txt"
ok "one report, of the last attempt" "[ \$(grep -c '^linear ' ref.txt) -eq 1 ] && [ \$(grep -c '\"name\": \"linear\"' ref.json) -eq 1 ]"
# splits that leave tangled elements, a remeshing, then splits that leave
# none (the bottle at --size 40 --curvature 4, 10 sweeps: the elements left
# tangled are on the faces at the thread's end, whose normal turns over
# next to it)
"$hocad" mesh "$bottle" --order 3 --size 40 --curvature 4 --max-iterations 10 --no-grading --no-output \
  --json spent.json > /dev/null 2> spenterr.txt
code=$?
ok "the split stage reports no optimisation" "grep -q '\"name\": \"split\"' spent.json && ! grep -q '\"name\": \"split\"[^}]*iterations' spent.json"
n_rem=$(grep -o '"remeshings": [0-9]*' spent.json | cut -d' ' -f2)
ok "split, remeshed, split until untangled (${n_rem:-none} remeshings)" "[ $code -eq 0 ] && grep -q 'meshing the faces again instead' spenterr.txt && [ -n '$n_rem' ] && [ '$n_rem' -ge 1 ] && [ \$(grep -c 'meshing their faces again' spenterr.txt) -eq '$n_rem' ] && tail -n 2 spenterr.txt | grep -q 'kept the mesh of refinement' && grep -q '\"name\": \"split\"' spent.json && grep -q '\"name\": \"optimized\".*\"tangled\": 0,' spent.json"
# one sweep: the splits leave elements tangled, and the first remeshing's
# finer mesh untangles in one sweep: no second remeshing, no split of it
"$hocad" mesh "$bottle" --order 3 --size 40 --curvature 3 --max-iterations 1 --no-grading --no-output \
  --json spent1.json > /dev/null 2> spent1err.txt
code=$?
ok "splits, then one remeshing that untangles" "[ $code -eq 0 ] && grep -q 'meshing the faces again instead' spent1err.txt && [ \$(grep -c 'meshing their faces again' spent1err.txt) -eq 1 ] && grep -q '\"remeshings\": 1,' spent1.json && grep -q '\"name\": \"optimized\".*\"tangled\": 0,' spent1.json"
lin_first=$(grep -o '"name": "linear"[^}]*' lim.json | grep -o '"elements": [0-9]*' | cut -d' ' -f2)
lin_last=$(grep -o '"name": "linear"[^}]*' ref.json | grep -o '"elements": [0-9]*' | cut -d' ' -f2)
ok "the last linear mesh is finer ($lin_first -> $lin_last)" "[ '$lin_last' -gt '$lin_first' ]"
# gmsh's own order-3 bottle (Debian's gmsh 4.8): straight triangles on the
# thread's face tangled. The optimiser leaves some tangled with the input's
# elements (exit 5 without splitting); with two splits per chain allowed
# it splits them and their neighbours red-green (optimising the new
# elements and two rings around them), and at their longest edges if
# that leaves some, until none is tangled by the exact test: the splits
# are made, counted and reported, and the file says what the report says.
if "$build/gmsh_ho_mesh" "$bottle" 3 g48.msh 2> /dev/null; then
  "$hocad" optimize "$bottle" g48.msh -o g48_kept.msh --refinements 0 -q --json g0.json \
    > /dev/null 2> g0.txt
  code=$?
  ok "without splitting: tangled left, exit 5" "[ $code -eq 5 ] && ! grep -q split g0.json"
  "$hocad" optimize "$bottle" g48.msh -o g48_split.msh --refinements 2 --json g1.json > g1.txt \
    2> g1err.txt
  code=$?
  n_split=$(grep -o '"refinements": [0-9]*' g1.json | cut -d' ' -f2)
  ok "splits said and counted (${n_split:-none})" "[ -n '$n_split' ] && [ '$n_split' -ge 1 ] && [ \$(grep -c 'splitting them' g1err.txt) -eq '$n_split' ]"
  ok "order 3: red-green splits optimised locally" "[ \$(grep -c 'red-green .* optimising the new elements and two rings around them again' g1err.txt) -ge 1 ] && [ \$(grep -c 'red-green' g1err.txt) -eq \$(grep -c 'red-green .* optimising the new elements and two rings around them again' g1err.txt) ]"
  t_out=$(grep -o '"name": "optimized"[^}]*' g1.json | grep -o '"tangled": [0-9]*' | cut -d' ' -f2)
  e_out=$(grep -o '"name": "optimized"[^}]*' g1.json | grep -o '"elements": [0-9]*' | cut -d' ' -f2)
  e_in=$(grep -o '"name": "input"[^}]*' g1.json | grep -o '"elements": [0-9]*' | cut -d' ' -f2)
  ok "none tangled left (${t_out:-none}): exit 0" "[ $code -eq 0 ] && [ '$t_out' = 0 ] && [ '${e_out:-0}' -gt '${e_in:-0}' ]"
  "$hocad" quality "$bottle" g48_split.msh --json gq.json > /dev/null 2>&1
  ok "the written mesh reads back as reported" "grep -q '\"tangled\": $t_out,' gq.json && grep -q '\"elements\": $e_out,' gq.json"
  # gmsh's linear mesh given: raised, optimised, still tangled, then split
  # as optimize splits, never meshed again (three splits per chain leave
  # none tangled)
  if "$build/gmsh_ho_mesh" "$bottle" 1 g48_lin.msh 2> /dev/null; then
    "$hocad" mesh "$bottle" --linear g48_lin.msh --order 3 --refinements 3 -o g48_lin3.msh \
      --json g3.json > /dev/null 2> g3err.txt
    code=$?
    ok "--linear: split made, untangled, no remeshing" "[ $code -eq 0 ] && grep -q '\"name\": \"high-order\"' g3.json && grep -q 'splitting them.* red-green' g3err.txt && ! grep -q 'meshing their faces again' g3err.txt && grep -q '\"remeshings\": 0,' g3.json"
  else
    ok "gmsh 4.8 meshes the bottle linear" "false"
  fi
  # one sweep cannot untangle: both chains of splits run in turn, twice
  # each, and the unsplit mesh, the least tangled, is kept
  "$hocad" optimize "$bottle" g48.msh -o g48_one.msh --max-iterations 1 --refinements 2 \
    --json g2.json > /dev/null 2> g2err.txt
  code=$?
  ok "two chains of splits in turn, exit 5" "[ $code -eq 5 ] && [ \$(grep -c 'splitting them.* red-green' g2err.txt) -eq 2 ] && [ \$(grep -c 'splitting them.* at their longest edges' g2err.txt) -eq 2 ] && grep -q '\"refinements\": 4,' g2.json && grep -q 'kept the mesh before it' g2err.txt"
else
  ok "gmsh 4.8 meshes the bottle" "false"
fi
# a split of the optimised mesh is optimised locally at high orders too
# (its new elements and two rings around them): one sweep leaves t20 raised to
# order 6 (not optimised: mesh would start it from order 3) tangled, and
# optimize splits it red-green, locally (the split at longest edges starts
# from the input and is optimised whole)
"$hocad" mesh "$model" --order 1 -o t20_lin.msh -q > /dev/null 2>&1
"$hocad" mesh "$model" --linear t20_lin.msh --order 6 --no-optimize -o t20_6.msh -q > /dev/null 2>&1
"$hocad" optimize "$model" t20_6.msh -o l6.msh --max-iterations 1 --refinements 1 \
  --repair-time none --json l6.json > /dev/null 2> l6err.txt
code=$?
ok "order 6: splits optimised locally, exit 5" "[ $code -eq 5 ] && grep -q 'red-green .* and optimising the new elements and two rings around them again' l6err.txt && grep -q '\"refinements\": 2,' l6.json"
# --repair-time: with a nanosecond for the repairs, the same run splits
# nothing and says why (rule 12)
"$hocad" optimize "$model" t20_6.msh -o l6t.msh --max-iterations 1 --refinements 1 \
  --repair-time 1e-9 --json l6t.json > /dev/null 2> l6terr.txt
code=$?
ok "--repair-time: no split past it, exit 5" "[ $code -eq 5 ] && ! grep -q 'splitting' l6terr.txt && grep -q 'the repairs took the 1e-09 s given them' l6terr.txt && grep -q '\"refinements\": 0,' l6t.json"
# a remeshing lowers the minimum size ten times, unless that more than
# quadruples the mesh: the bottle's curvature sizing at 8 elements per 2 pi
# then makes over 20 000 elements from gmsh's 4 566, and the faces are
# meshed again with the minimum size they had (a few more elements than
# 4 566; one sweep leaves some of them tangled: exit 5)
"$hocad" mesh "$bottle" --order 3 --size 40 --curvature 8 --max-iterations 1 --refinements 1 --no-grading \
  --no-output --json rm.json > /dev/null 2> rmerr.txt
code=$?
n_rm=$(grep -o '"name": "linear"[^}]*' rm.json | grep -o '"elements": [0-9]*' | cut -d' ' -f2)
ok "remeshing: minimum size kept when lowering it quadruples the mesh (${n_rm:-none})" "[ $code -eq 0 -o $code -eq 5 ] && grep -q 'more than four times the 4566 before: meshing them again with the minimum size 4\$' rmerr.txt && grep -q '\"remeshings\": 1,' rm.json && [ '${n_rm:-0}' -gt 4566 ] && [ '${n_rm:-0}' -lt 9132 ]"
# an untangled mesh with elements below 0.9 x the linear mesh's min q
# (periodic_u_cst at order 3 stopped after one sweep: 0.2022 against
# 0.2327): those elements and two rings around them optimised once more, a
# "smoothed" stage, kept because it raises the min q (to 0.2371)
cst=$src/examples/models/periodic_u_cst.step
"$hocad" mesh "$cst" --order 3 --max-iterations 1 --refinements 0 --threads 2 --no-output \
  --json sm.json > smout.txt 2> smerr.txt
code=$?
sm_lin=$(grep -o '"name": "linear"[^}]*' sm.json | grep -o '"min": [0-9.e-]*' | cut -d' ' -f2)
sm_opt=$(grep -o '"name": "optimized"[^}]*' sm.json | grep -o '"min": [0-9.e-]*' | cut -d' ' -f2)
sm_min=$(grep -o '"name": "smoothed"[^}]*' sm.json | grep -o '"min": [0-9.e-]*' | cut -d' ' -f2)
ok "low elements smoothed: $sm_opt -> $sm_min against linear $sm_lin" "[ $code -eq 0 ] && grep -q 'below 0.9 x the linear mesh' smerr.txt && grep -q '^smoothed ' smout.txt && awk -v l=\"$sm_lin\" -v a=\"$sm_opt\" -v b=\"$sm_min\" 'BEGIN{exit !(a < 0.9 * l && b > a && b >= 0.9 * l)}'"
# no temporary files left behind
ok "no temporaries" "[ -z \"\$(ls -A | grep tmp- || true)\" ]"
echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
