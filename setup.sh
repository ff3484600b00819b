#!/usr/bin/env bash
# Ambience set-up: installs missing Debian packages, configures into build/, builds,
# then runs the main job (`./setup.sh run`) or the test suite (`./setup.sh test`).
#
#   ./setup.sh run  [ambience run options]   install, build, render the default replay
#   ./setup.sh test                          install, build, run every test with ctest
#   ./setup.sh build                         install and build only
set -euo pipefail
cd "$(dirname "$0")"

mode="${1:-build}"
shift || true

packages=(
  cmake ninja-build g++ pkg-config python3-glad glslang-tools
  libegl-dev libegl-mesa0 libgl1-mesa-dri libosmesa6-dev libgles-dev libglfw3-dev
  libglm-dev libopenimageio-dev openimageio-tools libopenvdb-dev libboost-dev
  libboost-iostreams-dev libtbb-dev libgtest-dev libbenchmark-dev libcli11-dev
  nlohmann-json3-dev xvfb xauth ffmpeg python3-matplotlib libtsl-hopscotch-map-dev
  ccache clang libfuzzer-14-dev libclang-rt-14-dev fonts-dejavu-core
  libimgui-dev parallel python3-openvdb python3-imath dpkg-dev python3-optuna python3-sklearn
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if ((${#missing[@]})); then
  echo "setup: installing missing packages: ${missing[*]}"
  sudo=()
  if [[ $(id -u) -ne 0 ]]; then
    command -v sudo >/dev/null || { echo "setup: need root (or sudo) to install: ${missing[*]}" >&2; exit 2; }
    sudo=(sudo)
  fi
  "${sudo[@]}" apt-get update -qq
  DEBIAN_FRONTEND=noninteractive "${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
else
  echo "setup: all ${#packages[@]} packages present"
fi

jobs="$(nproc)"
if [[ ! -f build/CMakeCache.txt ]]; then
  # ccache (in the list above) makes a rebuild after a fresh clone or a clean cheap.
  cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache
fi
cmake --build build -j "$jobs"

case "$mode" in
  build) ;;
  run) exec build/bin/ambience run "$@" ;;
  test) cd build && exec ctest --output-on-failure -j "$jobs" "$@" ;;
  *) echo "setup: unknown mode '$mode' (expected run, test or build)" >&2; exit 2 ;;
esac
