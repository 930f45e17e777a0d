#!/usr/bin/env bash
# Installs the built hmsm into a temporary prefix, builds tests/consumers against it and runs
# every program: an engine linking the Vulkan loader (both link orders) and one with its own
# volk. FLAVOUR static or shared says which library TARGET (an installed hmsm target name) is;
# for shared, the programs must load libhmsm.so and the installed libraries' symbols are
# checked too.
# Usage: run.sh BUILD_DIR CONSUMERS_SOURCE_DIR [FLAVOUR TARGET]
set -euo pipefail
build="$1"; source_dir="$2"; flavour="${3:-static}"; target="${4:-hmsm::hmsm}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cmake --install "$build" --prefix "$work/prefix" >/dev/null
cmake -S "$source_dir" -B "$work/consumers" -G Ninja -DCMAKE_PREFIX_PATH="$work/prefix" \
  -DHMSM_TARGET="$target" >/dev/null
cmake --build "$work/consumers" >/dev/null
for program in loader_then_hmsm hmsm_then_loader own_volk; do
    echo "--- $program"
    "$work/consumers/$program"
    if [[ "$flavour" == shared ]]; then
        deps="$(ldd "$work/consumers/$program")"
        grep -q "libhmsm.so" <<<"$deps" || { echo "$program does not use libhmsm.so"; exit 1; }
    fi
done
if [[ "$flavour" == shared ]]; then
    "$(dirname "$0")/../boundary/check_symbols.sh" "$work"/prefix/lib*/libhmsm.a "$work"/prefix/lib*/libhmsm.so
fi
