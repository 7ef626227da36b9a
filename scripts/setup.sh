#!/usr/bin/env bash
# Installs what Kaskad needs from Debian 12 packages (as root, only what is missing), then
# configures and builds a CMake preset (default: release). Idempotent: a second run only rebuilds
# what changed.   usage: bash scripts/setup.sh [release|debug|asan]
set -euo pipefail
preset="${1:-release}"
cd "$(dirname "$0")/.."

packages=(
  cmake g++ make pkg-config git
  libglfw3-dev libegl-dev libepoxy-dev libglm-dev libgl-dev
  libegl-mesa0 libgl1-mesa-dri libglx-mesa0 libgl1 mesa-utils
  libtinygltf-dev libdraco-dev draco
  libopenimageio-dev openimageio-tools
  nlohmann-json3-dev libcli11-dev libxxhash-dev libimgui-dev libstb-dev libembree-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  python3-matplotlib python3-numpy python3-jsonschema xvfb xauth xdotool
)
bash scripts/install_packages.sh setup "${packages[@]}"

jobs="$(nproc 2>/dev/null || echo 2)"
cmake --preset "$preset" >/dev/null
cmake --build --preset "$preset" -j "$jobs"
