#!/usr/bin/env bash
# Install what hocad needs to build (and, with --test, to run its tests) from
# Debian's packages. Idempotent: installs only what is missing.
# SPDX-License-Identifier: GPL-2.0-or-later
set -euo pipefail

packages=(build-essential cmake libgmsh-dev libpng-dev zlib1g-dev)
if [ "${1:-}" = "--test" ]; then
  # the readers test (tests/test_io_readers.py) runs /usr/bin/python3 with these
  packages+=(valgrind clang libclang-rt-14-dev pngcheck python3-meshio python3-gmsh python3-vtk9
             python3-numpy python3-pytest)
fi

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0

if [ "$(id -u)" -eq 0 ]; then
  sudo=()
elif command -v sudo >/dev/null 2>&1; then
  sudo=(sudo)
else
  echo "deps.sh: need root (or sudo) to install: ${missing[*]}" >&2
  exit 1
fi
echo "installing: ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
"${sudo[@]}" apt-get update -q
"${sudo[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"
