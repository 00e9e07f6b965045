#!/usr/bin/env bash
# hocad render and hocad mesh --png: pictures that decode with an independent
# decoder (pngcheck), of the requested size, with and without the model.
# usage: cli_render.sh HOCAD SOURCE_DIR
set -u
hocad=$(readlink -f "$1")
src=$(readlink -f "$2")
pass=0
fail=0
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
ok() { if eval "$2"; then pass=$((pass + 1)); else fail=$((fail + 1)); echo "FAIL: $1" >&2; fi; }
# width and height from the IHDR chunk (bytes 17..24), read with od
png_size() { od -An -tu1 -j16 -N8 "$1" | awk '{printf "%dx%d", $1*16777216+$2*65536+$3*256+$4, $5*16777216+$6*65536+$7*256+$8}'; }
decodes() {
  if command -v pngcheck >/dev/null 2>&1; then pngcheck -q "$1" >/dev/null 2>&1
  else echo "note: pngcheck missing, only the signature is checked" >&2; head -c 8 "$1" | od -An -tx1 | grep -q '89 50 4e 47'; fi
}

model=$src/examples/models/gmsh_t20_component8.step
"$hocad" mesh "$model" --order 3 --png stages.png --histogram hist.png --png-size 900x400 \
  -o t20.msh > out.txt 2> err.txt
ok "mesh --png exits 0" "[ $? -eq 0 ]"
ok "stages picture decodes" "decodes stages.png"
ok "stages picture is 900x400 ($(png_size stages.png))" "[ $(png_size stages.png) = 900x400 ]"
ok "histogram decodes" "decodes hist.png"
ok "mesh says what it wrote" "grep -q 'wrote stages.png' out.txt && grep -q 'wrote hist.png' out.txt"

"$hocad" render t20.msh --model "$model" -o withmodel.png --view top --zoom-worst > r1.txt 2>&1
ok "render with model exits 0" "[ $? -eq 0 ]"
ok "render with model decodes" "decodes withmodel.png"
ok "render with model is 1600x1200 by default" "[ $(png_size withmodel.png) = 1600x1200 ]"
ok "render reports the quality" "grep -q '0 tangled' r1.txt"

"$hocad" render t20.msh -o nomodel.png --size 640x480 --no-edges --transparent \
  --histogram nh.png --view 1,-2,0.5 > r2.txt 2>&1
ok "render without model exits 0" "[ $? -eq 0 ]"
ok "render without model decodes" "decodes nomodel.png && decodes nh.png"
ok "render without model is 640x480" "[ $(png_size nomodel.png) = 640x480 ]"
# a raised, tangled mesh: both measures see the tangles
"$hocad" mesh "$model" --order 2 --no-optimize -o raised.msh > /dev/null 2>&1
"$hocad" render raised.msh --model "$model" -o tangled.png > r3.txt 2>&1
ok "render with model counts the 4 tangled" "grep -q ', 4 tangled' r3.txt"
"$hocad" render raised.msh -o tangled2.png > r4.txt 2>&1
ok "render without model sees tangles" "! grep -q ', 0 tangled' r4.txt"

# a failing render keeps the previous picture
echo previous > keep.png
"$hocad" render nosuch.msh -o keep.png > /dev/null 2>&1
ok "previous picture kept" "[ \"\$(cat keep.png)\" = previous ]"
ok "no temporaries" "[ -z \"\$(ls -A | grep tmp- || true)\" ]"
echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
