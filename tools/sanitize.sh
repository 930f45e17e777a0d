#!/usr/bin/env bash
# Builds the whole test suite with AddressSanitizer + UndefinedBehaviorSanitizer (Debug, so the
# golden hashes are also checked unoptimized) in ${HMSM_ASAN_BUILD_DIR:-build-asan} and runs it.
# Any sanitizer report fails the run (-fno-sanitize-recover=all; halt_on_error). The Vulkan
# backend is left out unless HMSM_SANITIZE_VULKAN=ON: the uninstrumented Mesa driver's own
# allocations would show up as leaks. Extra arguments go to cmake.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${HMSM_ASAN_BUILD_DIR:-$root/build-asan}"
jobs="$(nproc 2>/dev/null || echo 2)"
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Debug -DHMSM_SANITIZE=ON -DHMSM_CUDA=OFF \
  -DHMSM_VULKAN="${HMSM_SANITIZE_VULKAN:-OFF}" "$@" >/dev/null
cmake --build "$build" -j "$jobs"
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:halt_on_error=1:abort_on_error=0:detect_stack_use_after_return=1:strict_string_checks=1:check_initialization_order=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
cd "$build"
ctest --output-on-failure -j "$jobs"
