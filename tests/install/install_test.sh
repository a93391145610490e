#!/usr/bin/env bash
# The installed package works for a program of a user's own (docs/design.md §4 "Install"):
#   1. `cmake --install BUILD --prefix TMP/prefix` of a built tree;
#   2. every `#include "..."` of an installed header names an installed header, and bin/ holds
#      only the raycell command (no test or benchmark);
#   3. tests/install/consumer configured with CMAKE_PREFIX_PATH=TMP/prefix (find_package(raycell),
#      raycell::traces) and built: the headers, libraries and dependencies it finds are the
#      installed ones only;
#   4. the consumer writes a two-frame trace and reads it back, exiting non-zero unless the rays
#      read are exactly the rays written;
#   5. the installed `raycell trace info` reads that trace, and the plot scripts are in
#      share/raycell, where `raycell study` looks for them.
# Usage: install_test.sh BUILD CONSUMER_SOURCE [cmake=..] [generator=..] [make=..] [cc=..] [cxx=..]
#        [launcher=..] [build_type=..] [cxx_flags=..] [link_flags=..]
# The temporary folder is removed on every exit.
set -euo pipefail

build=$1 consumer_src=$2
shift 2
cmake=cmake generator="" make="" cc="" cxx="" launcher="" build_type="" cxx_flags="" link_flags=""
for arg; do
  case $arg in
    cmake=* | generator=* | make=* | cc=* | cxx=* | launcher=* | build_type=* | cxx_flags=* | link_flags=*)
      declare "${arg%%=*}=${arg#*=}" ;;
    *) echo "install_test.sh: unknown argument '$arg'" >&2; exit 2 ;;
  esac
done

tmp=$(mktemp -d "${TMPDIR:-/tmp}/raycell_install_test.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
prefix=$tmp/prefix
fail() { echo "install_test: FAIL: $*" >&2; exit 1; }
run() {  # run a step quietly, printing its output when it fails
  local log=$tmp/step.log
  "$@" >"$log" 2>&1 || { cat "$log" >&2; fail "$*"; }
}

# 1. Install.
run "$cmake" --install "$build" --prefix "$prefix"

# 2. The installed headers are complete and nothing but the command is in bin/.
include=$prefix/include/raycell
[[ -f $include/traces/trace_reader.h && -f $include/traces/trace.capnp ]] ||
  fail "no traces/trace_reader.h or traces/trace.capnp under $include"
while IFS= read -r header; do
  while IFS= read -r name; do
    [[ -f $include/$name ]] || fail "${header#"$include"/} includes \"$name\", not installed"
  done < <(sed -n 's/^#include "\(.*\)".*/\1/p' "$header")
done < <(find "$include" -name '*.h')
bin=$(find "$prefix/bin" -mindepth 1 -printf '%f ')
[[ $bin == "raycell " ]] || fail "bin/ holds $bin; expected only raycell"

# 3. Configure and build the consumer against the installed package.
args=(-S "$consumer_src" -B "$tmp/consumer" -DCMAKE_PREFIX_PATH="$prefix"
      -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF)
[[ -n $generator ]] && args+=(-G "$generator")
[[ -n $make ]] && args+=(-DCMAKE_MAKE_PROGRAM="$make")
[[ -n $cc ]] && args+=(-DCMAKE_C_COMPILER="$cc")
[[ -n $cxx ]] && args+=(-DCMAKE_CXX_COMPILER="$cxx")
[[ -n $launcher ]] && args+=(-DCMAKE_CXX_COMPILER_LAUNCHER="$launcher")
[[ -n $build_type ]] && args+=(-DCMAKE_BUILD_TYPE="$build_type")
args+=(-DCMAKE_CXX_FLAGS="$cxx_flags" -DCMAKE_EXE_LINKER_FLAGS="$link_flags")
run "$cmake" "${args[@]}"
run "$cmake" --build "$tmp/consumer"

# 4. Write and read back a trace with the installed library.
"$tmp/consumer/consumer" "$tmp/two_frames.rct" || fail "the consumer's round trip"

# 5. The installed command reads it; the plot scripts are installed.
info=$("$prefix/bin/raycell" trace info "$tmp/two_frames.rct") ||
  fail "installed raycell trace info exited $?"
# The consumer's frames 4 and 5, counted by hand: 3 primary, 1 reflection, 1 refraction and
# 1 shadow ray, 6 + 3 visits, 12+7+3+4+9+1 + 100000+2+5 samples.
frames_line=$'\n''frames: +2'$'\n'
total_line='total +3 +1 +1 +1 +6 +9 +100043 '
[[ $info =~ $frames_line && $info =~ $total_line ]] ||
  fail "raycell trace info does not show the 2 frames and 6 rays written: $info"
for script in plot_study.py plot_accuracy.py; do
  [[ -f $prefix/share/raycell/$script ]] || fail "share/raycell/$script not installed"
done
echo "install_test: installed, consumer built and round-tripped a trace, raycell trace info read it"
