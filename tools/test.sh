#!/usr/bin/env bash
# The README's test command: installs what is missing, builds, runs every test (CTest).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/tools/install_deps.sh"
"$root/tools/build.sh" "$@"
build="${HMSM_BUILD_DIR:-$root/build}"
cd "$build"
ctest --output-on-failure -j "$(nproc 2>/dev/null || echo 2)"
# Hard to break: the whole suite under ASan + UBSan (Debug, in build-asan), the threading
# contract under ThreadSanitizer (build-tsan, the library and one test executable), then each
# libFuzzer target on the parsers for HMSM_FUZZ_SECONDS (default 60). HMSM_HARDENING=0 skips them.
if [ "${HMSM_HARDENING:-1}" != 0 ]; then
  "$root/tools/sanitize.sh"
  "$root/tools/tsan.sh"
  "$root/tools/fuzz.sh"
fi
