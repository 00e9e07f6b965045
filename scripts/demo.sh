#!/usr/bin/env bash
# Build hocad and run it on a bundled model: linear mesh, order 3, quality
# report; writes build/demo/*.{msh,vtu,json}.
# SPDX-License-Identifier: GPL-2.0-or-later
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DHOCAD_TESTS=OFF >/dev/null
cmake --build build -j "$(nproc)"
mkdir -p build/demo
model=${1:-examples/models/gmsh_t20_component8.step}
name=$(basename "${model%.*}")
./build/hocad mesh "$model" --order 3 -o "build/demo/${name}_p3.msh" \
  --vtu "build/demo/${name}_p3.vtu" --json "build/demo/${name}_p3.json" \
  --png "build/demo/${name}_p3.png"
