#!/usr/bin/env bash
# Installs what raycell needs on Debian 12 (apt) and builds it into build/.
#
# Usage: tools/setup.sh [--tests] [extra cmake arguments, e.g. -DRAYCELL_SANITIZE=ON]
#   without --tests  the packages the main job needs, then the `raycell` binary alone, its
#                    libraries compiled as unity builds: the README's first command gives a
#                    report within minutes (BENCHMARKS.md "First result and build time")
#   --tests          also the packages of the tests and of CI's extra checks, then every
#                    target: tests, fuzz corpus runners, benchmarks (the README's test command)
set -euo pipefail
cd "$(dirname "$0")/.."

tests=0
if [ "${1:-}" = "--tests" ]; then
  tests=1
  shift
fi

packages=(
  build-essential cmake ninja-build pkg-config
  libopenvdb-dev libboost-iostreams-dev libtbb-dev                   # scenes and rendering
  capnproto libcapnp-dev libzstd-dev                                 # the trace file
  libcli11-dev libpng-dev libboost-graph-dev libtomlplusplus-dev     # CLI, images, graphs, configs
  libglpk-dev                    # the lower bound's integer program (bounds/lower_bound.cpp)
  python3 python3-matplotlib                                         # the study's plots
)
if ((tests)); then
  packages+=(
    git clang-format libgtest-dev libgmock-dev                       # tests, formatting check
    libopenvdb-tools zstd bc graphviz                                # vdb_render, benchmarks, DOT
    clang libclang-rt-14-dev  # .ci/run: the ASan/UBSan build and libFuzzer targets (RAYCELL_FUZZ)
  )
fi

start=$SECONDS
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}"
  sudo=""
  if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
echo "setup: packages took $((SECONDS - start)) s"
start=$SECONDS

# Unity builds compile each library in a few translation units: the first build of `raycell`
# takes about 0.6 of the time (BENCHMARKS.md "First result and build time"). Tests and fuzz
# targets are compiled one file each either way.
# Ninja schedules the two cores better than Make here (BENCHMARKS.md "First result and build
# time"); a build/ configured before keeps its generator.
generator=(-G Ninja)
if [ -f build/CMakeCache.txt ]; then generator=(); fi
cmake -S . -B build "${generator[@]}" -DCMAKE_BUILD_TYPE=Release -DRAYCELL_UNITY_BUILD=ON "$@"
if ((tests)); then
  cmake --build build -j"$(nproc)"
else
  cmake --build build -j"$(nproc)" --target raycell
fi
echo "setup: configure and build took $((SECONDS - start)) s"
