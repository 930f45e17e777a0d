#!/usr/bin/env bash
# Builds the libFuzzer targets (tests/fuzz, clang, -fsanitize=fuzzer,address,undefined) and runs
# each for a bounded time on the seed corpus (valid trees, forests, schedules and cylinder models plus the bad-input
# catalog). Exit 0 when nothing was found; otherwise the crashing input is under
# $build/artifacts/ and the script fails.
#   HMSM_FUZZ_BUILD_DIR  build folder (default build-fuzz)
#   HMSM_FUZZ_SECONDS    seconds per target (default 60)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${HMSM_FUZZ_BUILD_DIR:-$root/build-fuzz}"
seconds="${HMSM_FUZZ_SECONDS:-60}"
cxx="${HMSM_FUZZ_CXX:-$(command -v clang++ || command -v clang++-14 || true)}"
[ -n "$cxx" ] || { echo "fuzz.sh: clang++ not found (tools/install_deps.sh installs it)" >&2; exit 1; }

cmake -S "$root/tests/fuzz" -B "$build" -G Ninja -DCMAKE_CXX_COMPILER="$cxx" >/dev/null
cmake --build "$build" -j "$(nproc 2>/dev/null || echo 2)"

mkdir -p "$build/artifacts"
status=0
for target in tree forest schedule treeqsm simpleforest import_size; do
  work="$build/corpus-$target"  # new inputs land here; the seed folders stay untouched
  mkdir -p "$work"
  seeds=("$root/tests/fuzz/corpus/$target" "$root/tests/fuzz/regressions/$target"
         "$root/tests/data/bad/${target}s")
  [ "$target" = import_size ] && seeds=("$root/tests/fuzz/corpus/import_size")
  echo "fuzz.sh: fuzz_$target for ${seconds} s" >&2
  # -max_len bounds an input (the deep-nesting seeds are larger and get truncated to it);
  # -timeout flags any input that takes more than 10 s as a hang; -rss_limit_mb bounds the memory
  # any one input may take (the parsers size their inputs before allocating).
  dict=()  # the JSON dictionary helps the JSON parsers only
  case $target in tree|forest|schedule) dict=(-dict="$root/tests/fuzz/json.dict") ;; esac
  if ! "$build/fuzz_$target" "$work" "${seeds[@]}" \
      "${dict[@]}" -max_total_time="$seconds" -max_len=16384 \
      -timeout=10 -rss_limit_mb=512 -print_final_stats=1 \
      -artifact_prefix="$build/artifacts/$target-" >"$build/fuzz_$target.log" 2>&1; then
    echo "fuzz.sh: fuzz_$target FAILED; the last lines of $build/fuzz_$target.log:" >&2
    tail -n 40 "$build/fuzz_$target.log" >&2
    status=1
  else
    grep -E "^stat::(number_of_executed_units|new_units_added|peak_rss_mb)" "$build/fuzz_$target.log" \
      | sed "s/^/fuzz.sh: fuzz_$target /" >&2 || true
  fi
done
exit $status
