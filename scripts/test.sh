#!/usr/bin/env bash
# Build hocad and run the whole test suite: a release build, a 60 s fuzzing
# run of the MSH reader, then the suite again under AddressSanitizer and
# UndefinedBehaviorSanitizer. Ends with ctest's summary.
# SPDX-License-Identifier: GPL-2.0-or-later
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh --test
jobs=$(nproc)

echo "== release build"
# HOCAD_TESTS=ON explicitly: the demo configures the same build directory
# with the tests off, and the cache would keep that.
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DHOCAD_TESTS=ON >/dev/null
cmake --build build -j "$jobs"
(cd build && ctest --output-on-failure --no-tests=error -j "$jobs")

echo "== fuzzing the MSH reader (60 s, libFuzzer, from tests/fuzz/corpus)"
CC=clang cmake -S . -B build-fuzz -DHOCAD_FUZZ=ON -DHOCAD_TESTS=OFF >/dev/null
cmake --build build-fuzz --target fuzz_msh -j "$jobs"
corpus=$(mktemp -d)
cp tests/fuzz/corpus/* "$corpus"/
./build-fuzz/tests/fuzz/fuzz_msh -max_total_time=60 -rss_limit_mb=2048 "$corpus" 2>&1 | tail -1
rm -rf "$corpus"

echo "== sanitizer build (ASan + UBSan)"
cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DHOCAD_SANITIZE=ON -DHOCAD_TESTS=ON >/dev/null
cmake --build build-asan -j "$jobs"
(cd build-asan && ASAN_OPTIONS=detect_leaks=1 ctest --output-on-failure --no-tests=error -j "$jobs")
