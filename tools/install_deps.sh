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
  clang libclang-rt-14-dev)  # clang + compiler-rt: libFuzzer (tools/fuzz.sh)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0
echo "hmsm: installing ${missing[*]}" >&2
sudo_cmd=()
[ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
