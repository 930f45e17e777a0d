#!/usr/bin/env bash
# The threading contract (include/hmsm/simulation.h, docs/engine.md) under ThreadSanitizer:
# builds the library and tests/boundary's threading tests with -fsanitize=thread (RelWithDebInfo,
# in ${HMSM_TSAN_BUILD_DIR:-build-tsan}) and runs them: simulations stepping in parallel,
# concurrent reads of one simulation (CPU and Vulkan), Vulkan simulations created from two
# threads at once, update_lod examining thousands of instances on the readback threads, the C
# ABI's per-thread message, and live control and streaming (instances added, removed and reset,
# wind and fields replaced) in several threads. Any report fails the run. Extra arguments go to
# cmake.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${HMSM_TSAN_BUILD_DIR:-$root/build-tsan}"
jobs="$(nproc 2>/dev/null || echo 2)"
flags="-fsanitize=thread -fno-omit-frame-pointer"
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DHMSM_CUDA=OFF \
  -DCMAKE_C_FLAGS="$flags" -DCMAKE_CXX_FLAGS="$flags" \
  -DCMAKE_EXE_LINKER_FLAGS=-fsanitize=thread -DCMAKE_SHARED_LINKER_FLAGS=-fsanitize=thread \
  "$@" >/dev/null
cmake --build "$build" -j "$jobs" --target hmsm_boundary_tests
# The Mesa driver and the validation layer are not instrumented: their internal threads are
# synchronized in ways TSan cannot see (tools/tsan.supp); hmsm's own code is fully checked.
export TSAN_OPTIONS="${TSAN_OPTIONS:-halt_on_error=1 second_deadlock_stack=1 suppressions=$root/tools/tsan.supp}"
HMSM_VULKAN_VALIDATION=1 "$build/tests/boundary/hmsm_boundary_tests" --gtest_filter='Threading.*:*/Threading.*'
