#!/usr/bin/env bash
# Installs what vff needs to build, test and run, from Debian 12's archive. Idempotent: when every
# package is already installed it changes nothing and needs no network.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config git
  libembree-dev libopenexr-dev openexr libopenvdb-dev libnanovdb-dev libopenvdb-tools libboost-iostreams-dev
  libopenmesh-dev libtinygltf-dev libdraco-dev libmeshoptimizer-dev libcli11-dev libzstd-dev libxxhash-dev
  nlohmann-json3-dev
  libstb-dev libtbb-dev libgtest-dev libgmock-dev libbenchmark-dev glslang-tools
  libegl-dev libgl-dev libopengl-dev libegl-mesa0 libgl1-mesa-dri
  libvulkan-dev mesa-vulkan-drivers vulkan-validationlayers vulkan-tools spirv-cross
  clang libclang-rt-14-dev
  glmark2-data zstd xz-utils python3 universal-ctags
  python3-dev pybind11-dev python3-pybind11 python3-numpy python3-pytest python3-matplotlib
  chromium nodejs
  slurm-wlm munge
)
# npm ships inside some nodejs builds; Debian packages it apart.
command -v npm >/dev/null 2>&1 || packages+=(npm)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
install_web() {
  # web/'s JavaScript dependencies, pinned by web/package-lock.json (the browser tests and the page).
  local web
  web="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)/web"
  if [ -f "$web/package-lock.json" ] && ! cmp -s "$web/package-lock.json" "$web/node_modules/.vff-lock" 2>/dev/null; then
    echo "setup: npm ci in web/"
    (cd "$web" && npm ci --no-audit --no-fund --loglevel=error && cp package-lock.json node_modules/.vff-lock)
  fi
}

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} packages present"
  install_web
  exit 0
fi

echo "setup: installing ${missing[*]}"
sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
install_web
