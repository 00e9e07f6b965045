# Shared by the bench scripts (sourced, not run): the project's root, gmsh,
# a work directory removed on exit, and readers of hocad's JSON report.
# SPDX-License-Identifier: GPL-2.0-or-later
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)

# pick_gmsh [GMSH]: the given gmsh, else the 5.0 peer of ../shared/peers,
# else Debian's gmsh on the PATH (empty if none).
pick_gmsh() {
  local g=${1:-$here/../shared/peers/gmsh-5.0-dev}
  [ -x "$g" ] || g=$(command -v gmsh || true)
  echo "$g"
}

# need_time: stop unless GNU time is there (Debian's package `time`, not the
# shell's keyword); the scripts that take peak memory with it call this, as
# without it every run would look like a failure of hocad.
need_time() {
  if [ ! -x /usr/bin/time ]; then
    echo "bench: /usr/bin/time is missing: apt-get install time" >&2
    exit 1
  fi
}

# use_hocad [HOCAD]: set hocad to the given hocad, else build/hocad, as an
# absolute path; stop unless it is an executable (the CLI's target is
# hocad-cli, built with the bench target: `cmake --build build --target
# bench`).
use_hocad() {
  hocad=$(readlink -f "${1:-$here/build/hocad}")
  if [ ! -x "$hocad" ] || [ -d "$hocad" ]; then
    echo "bench: no hocad at ${1:-$here/build/hocad}: cmake --build build --target bench" >&2
    exit 1
  fi
}

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# jget FILE STAGE KEY: a number of one stage of hocad's JSON report
jget() { grep -o "\"name\": \"$2\"[^}]*" "$1" | grep -o "\"$3\": [-0-9.e+a-z]*" | head -1 | cut -d' ' -f2; }
# jtop FILE KEY: a top-level number of the report
jtop() { grep -o "\"$2\": [-0-9.e+]*" "$1" | head -1 | cut -d' ' -f2; }
# rss_mb FILE: peak RSS in MB from /usr/bin/time -f %M (its last line: a
# failed command's status line comes first)
rss_mb() { tail -n 1 "$1" | awk '{print $1 / 1024}'; }

# bench_header ARGS...: markdown lines to paste above a table: the command
# that made it (the calling script with ARGS), the machine (cores, CPU,
# memory, load when it started) and the hocad that ran (the repository's
# git describe, the binary's --version); needs $hocad (use_hocad) set.
bench_header() {
  local script cpu mem rev
  script=${0#"$here"/}
  cpu=$(awk -F': *' '/^model name/ { print $2; exit }' /proc/cpuinfo)
  mem=$(awk '/^MemTotal/ { printf "%.0f GiB", $2 / 1048576 }' /proc/meminfo)
  rev=$(git -C "$here" describe --always --tags --dirty 2>/dev/null || echo "not a git checkout")
  printf 'Command: `bash %s' "$script"
  local a
  for a in "$@"; do
    case $a in
      *[!-A-Za-z0-9_./=,:+]*) printf " '%s'" "$a" ;;
      *) printf ' %s' "$a" ;;
    esac
  done
  printf '`\n\n'
  printf 'Machine: %s cores (%s), %s, load %s at the start; hocad %s (%s, %s); %s.\n\n' \
    "$(env -u OMP_NUM_THREADS -u OMP_THREAD_LIMIT nproc)" "${cpu:-unknown CPU}" "$mem" "$(cut -d' ' -f1-3 /proc/loadavg)" "$rev" \
    "$("$hocad" --version 2>/dev/null | head -n 1)" "$hocad" "$(date -u '+%Y-%m-%d %H:%M UTC')"
}
