#!/usr/bin/env bash
# Installs the Debian packages hmsm needs, only those missing. Needs root (or sudo) on a machine
# that lacks them; does nothing when everything is present.
set -euo pipefail
packages=(cmake ninja-build g++ pkg-config
  libvulkan-dev mesa-vulkan-drivers vulkan-tools vulkan-validationlayers glslang-tools spirv-tools
  libglm-dev libvulkan-volk-dev libgtest-dev libgmock-dev libbenchmark-dev
  nlohmann-json3-dev libcli11-dev
  libpng-dev libgif-dev libstb-dev  # libpng, giflib: hmsm render; stb_image: its tests
  python3  # examples/python, the C ABI example CTest runs
  clang libclang-rt-14-dev  # clang + compiler-rt: libFuzzer (tools/fuzz.sh)
  libtinygltf-dev nodejs)  # hmsm export --gltf; node: the Khronos glTF validator (tools/gltf)
# Node's npm: Debian's package, unless a Node.js distribution that bundles it is installed.
command -v npm >/dev/null 2>&1 || packages+=(npm)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "hmsm: installing ${missing[*]}" >&2
  sudo_cmd=()
  [ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
  export DEBIAN_FRONTEND=noninteractive
  "${sudo_cmd[@]}" apt-get update -qq
  "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
# The Khronos glTF validator and three.js (the export tests and viewer), pinned by
# tools/gltf/package-lock.json, into tools/gltf/node_modules (ignored by git).
gltf="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)/gltf"
if [ ! -f "$gltf/node_modules/gltf-validator/package.json" ] || [ ! -f "$gltf/node_modules/three/package.json" ]; then
  echo "hmsm: installing the glTF validator and three.js (npm ci in $gltf)" >&2
  npm ci --prefix "$gltf" --no-audit --no-fund >/dev/null
fi
