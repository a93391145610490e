#!/usr/bin/env bash
# Installs what raycell needs on Debian 12 (apt) and builds it into build/.
# Usage: tools/setup.sh [extra cmake arguments, e.g. -DRAYCELL_SANITIZE=ON]
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(
  build-essential cmake pkg-config git clang-format
  libopenvdb-dev libopenvdb-tools libboost-iostreams-dev libtbb-dev  # scenes and rendering
  capnproto libcapnp-dev libzstd-dev zstd                            # the trace file
  libcli11-dev libpng-dev libboost-graph-dev libtomlplusplus-dev     # CLI, images, graphs, configs
  libgtest-dev libgmock-dev                                          # tests
  libglpk-dev                    # the lower bound's integer program (bounds/lower_bound.cpp)
  python3 python3-matplotlib bc graphviz                             # plots, DOT, benchmarks
  clang libclang-rt-14-dev  # .ci/run: the ASan/UBSan build and libFuzzer targets (RAYCELL_FUZZ)
)

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

cmake -S . -B build -DCMAKE_BUILD_TYPE=Release "$@"
cmake --build build -j"$(nproc)"
