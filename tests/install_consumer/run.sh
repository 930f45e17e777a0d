#!/usr/bin/env bash
# Installs the built hmsm into a temporary prefix and builds and runs a consumer against it,
# with the CUDA toolkit made unfindable: a consumer needs no CUDA to link or run hmsm.
set -euo pipefail
build="$1"; source_dir="$2"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cmake --install "$build" --prefix "$work/prefix" >/dev/null
cmake -S "$source_dir" -B "$work/consumer" -G Ninja -DCMAKE_PREFIX_PATH="$work/prefix" \
  -DCMAKE_DISABLE_FIND_PACKAGE_CUDAToolkit=ON >/dev/null
cmake --build "$work/consumer" >/dev/null
"$work/consumer/consumer"
