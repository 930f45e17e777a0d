#!/usr/bin/env bash
# Runs `hmsm bench` on the lent NVIDIA machine (through the `device` tool, from the repository
# root, carrying the build folder and .gl, the Vulkan loader packages; see tools/gpu/run.sh):
#
#   bash tools/bench_gpu.sh [BUILD_DIR] [COMMIT]      (default build-gpu, unknown)
#
# HMSM_BENCH_ARGS adds `hmsm bench` flags (e.g. "--presets paper-1,paper-5 --repeats 3").
#
# Writes $OUT/bench.json (the result), $OUT/bench.md (its tables), $OUT/bench.err (progress,
# skips) and $OUT/gpu.txt. Back on the development machine, the device's page
# (docs/benchmarks/README.md):
#   build/hmsm bench --render <fetched>/bench.json --out docs/benchmarks/nvidia-h100
set -u
BUILD=${1:-build-gpu}
COMMIT=${2:-unknown}
OUT=${OUT:-/tmp/hmsm-bench-out}
mkdir -p "$OUT"
if compgen -G ".gl/*.deb" >/dev/null; then
    for f in .gl/*.deb; do dpkg -x "$f" /; done
    ldconfig
fi
# Shared libraries the CLI links that the GPU machine lacks (libgif for `hmsm render`), copied
# from the build machine into .gl/lib (see tools/gpu/run.sh).
[[ -d .gl/lib ]] && export LD_LIBRARY_PATH=$PWD/.gl/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
ICD=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
[[ -f $ICD ]] && export VK_DRIVER_FILES=$ICD
nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.sm,clocks.max.sm --format=csv >"$OUT/gpu.txt" 2>&1
# The device tool stops a command at 600 s; the case budget keeps the serial CPU baseline's
# forest to a few minutes (sizes it cannot finish are skipped with the estimate).
timeout --kill-after=5 ${HMSM_BENCH_LIMIT:-560} "$BUILD/hmsm" bench --backends cpu,cpu-parallel,cuda,vulkan ${HMSM_BENCH_ARGS:-} \
    --case-budget ${HMSM_BENCH_BUDGET:-15} --json "$OUT/bench.json" --commit "$COMMIT" \
    >"$OUT/bench.md" 2>"$OUT/bench.err"
rc=$?
echo "hmsm bench rc=$rc"
tail -n 5 "$OUT/bench.err"
cat "$OUT/bench.md"
exit $rc
