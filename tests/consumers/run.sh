#!/usr/bin/env bash
# Installs the built hmsm into a temporary prefix, builds tests/consumers against it and runs
# every program: an engine linking the Vulkan loader (both link orders) and one with its own
# volk. Usage: run.sh BUILD_DIR CONSUMERS_SOURCE_DIR
set -euo pipefail
build="$1"; source_dir="$2"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cmake --install "$build" --prefix "$work/prefix" >/dev/null
cmake -S "$source_dir" -B "$work/consumers" -G Ninja -DCMAKE_PREFIX_PATH="$work/prefix" >/dev/null
cmake --build "$work/consumers" >/dev/null
for program in loader_then_hmsm hmsm_then_loader own_volk; do
    echo "--- $program"
    "$work/consumers/$program"
done
