#!/usr/bin/env bash
# Runs hmsm's GPU checks on the lent NVIDIA machine, called through the `device` tool from the
# repository root with the build folder carried from the development machine (nothing is built
# there):
#
#   bash tools/gpu/run.sh [BUILD_DIR]        (default: build-gpu; carry BUILD_DIR and .gl)
#
# In order, each under its own time limit inside the device tool's 10 minutes: unpack the
# carried Vulkan loader (.gl/*.deb, see the device README), the CUDA suite, the core suite's
# backend agreement tests (CUDA and Vulkan against cpu64), the Vulkan suite if built,
# compute-sanitizer memcheck, racecheck, initcheck and synccheck over the CUDA suite, a
# `hmsm simulate --backend cuda` run and `hmsm bench` if the CLI has it. Logs go to $OUT
# (8 files at most: summary, four logs of suites and sanitizers, cli.log,
# report_cuda.json, bench.json); summary.log gathers the lines that matter and ends with a short table.
set -u
BUILD=${1:-build-gpu}
OUT=${OUT:-/tmp/hmsm-gpu-out}
mkdir -p "$OUT"
SUMMARY=$OUT/summary.log
DEADLINE=${HMSM_GPU_DEADLINE:-570}  # seconds; the device tool stops a command at 600
: >"$SUMMARY"

say() { echo "$*" | tee -a "$SUMMARY"; }
# run_step SECONDS LOG COMMAND...: runs COMMAND with stdout+stderr appended to LOG, stopped
# after SECONDS or at the deadline, whichever comes first; records its exit status.
run_step() {
    local budget=$1 log=$2
    shift 2
    local left=$((DEADLINE - SECONDS - 5))
    if ((left < 15)); then
        say "SKIPPED (no time left): $*"
        return 0
    fi
    ((budget > left)) && budget=$left
    echo "### $* (limit ${budget}s)" >>"$log"
    local start=$SECONDS
    timeout --kill-after=5 "$budget" "$@" >>"$log" 2>&1
    local rc=$?
    say "rc=$rc in $((SECONDS - start))s: $*"
    return 0
}

# --- environment -----------------------------------------------------------------------
if compgen -G ".gl/*.deb" >/dev/null; then
    for f in .gl/*.deb; do dpkg -x "$f" /; done
    ldconfig
fi
export PATH=$PATH:/usr/local/cuda/bin
# Shared libraries the CLI links that the GPU machine lacks (e.g. libgif for `hmsm render`),
# copied from the build machine into .gl/lib.
[[ -d .gl/lib ]] && export LD_LIBRARY_PATH=$PWD/.gl/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
ICD=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
[[ -f $ICD ]] && export VK_DRIVER_FILES=$ICD
# The Khronos validation layer, carried as a package in .vvl (unpacked outside /): with it the
# Vulkan tests run under validation and synchronization validation, and any message fails them.
if compgen -G ".vvl/vulkan-validationlayers_*.deb" >/dev/null; then
    dpkg -x .vvl/vulkan-validationlayers_*.deb /tmp/vvl
    export VK_LAYER_PATH=/tmp/vvl/usr/share/vulkan/explicit_layer.d
    export LD_LIBRARY_PATH=/tmp/vvl/usr/lib/x86_64-linux-gnu${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
    export HMSM_VULKAN_VALIDATION=1 HMSM_VULKAN_REQUIRE_VALIDATION=1
fi
say "== $(date -u +%FT%TZ) build=$BUILD validation=${HMSM_VULKAN_VALIDATION:-0}"
nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.sm,clocks.max.sm --format=csv,noheader 2>&1 | tee -a "$SUMMARY"

CUDA_TESTS=$BUILD/tests/cuda/hmsm_cuda_tests
CORE_TESTS=$BUILD/tests/hmsm_tests
VULKAN_TESTS=$BUILD/tests/vulkan/hmsm_vulkan_tests
RENDER_TESTS=$BUILD/tests/hmsm_render_tests
CLI=$BUILD/hmsm
# Tests that cannot be sanitizer-clean by design: a deliberate out-of-memory cudaMalloc (an API
# error to the sanitizer) and a deliberate device fault in a child process.
SANITIZER_FILTER='-CudaErrors.OutOfMemory*:CudaErrorsStickyDeathTest.*'

# --- suites ----------------------------------------------------------------------------
# From the core suite the backend agreement tests (every backend against cpu64); the rest of
# it needs no GPU (and its CLI tests run the CLI by its build-machine path).
# The NVIDIA driver refuses new VkInstances after about 68 in one process, so the suites that
# create many run as gtest shards, each its own process.
run_sharded() {  # run_sharded SHARDS SECONDS LOG COMMAND...
    local shards=$1 budget=$2 log=$3
    shift 3
    for ((k = 0; k < shards; ++k)); do
        run_step "$budget" "$log" env GTEST_TOTAL_SHARDS="$shards" GTEST_SHARD_INDEX="$k" "$@"
    done
}
[[ -x $CORE_TESTS ]] && run_sharded 3 60 "$OUT/core_tests.log" "$CORE_TESTS" --gtest_filter='*Agreement*:*Determinism*:*LiveControl*:*LiveReshape*:*Joints*:*Golden*:CpuParallel.*:Threading.*:PassTable.*:*ResetInstances*:Limits.*:CSkin.*:*ReadAsync*:*LevelSimulation*:*Handle*:*Atmospheric*:*Coupled*:*LodSwitch*:*LodFade*:*JointsState*:*Streaming*:*ReadLarge*:*RangeTransfers*:*StepProgram*:*Listed*:-*Cli*'
[[ -x $VULKAN_TESTS ]] && run_sharded 4 60 "$OUT/vulkan_tests.log" "$VULKAN_TESTS"
# The engine-loop example: an engine-owned device drawing the skinned tree (exit 77: skipped).
ENGINE_LOOP=$BUILD/examples/hmsm_example_engine_loop
[[ -x $ENGINE_LOOP ]] && run_step 60 "$OUT/vulkan_tests.log" "$ENGINE_LOOP" /tmp/hmsm-engine-loop
# The renderer on the NVIDIA driver (its CLI tests run the CLI by its build-machine path).
[[ -x $RENDER_TESTS ]] && run_step 60 "$OUT/vulkan_tests.log" "$RENDER_TESTS" --gtest_filter='-RenderCli.*'
# The CUDA suite last: its sticky-error test faults the GPU on purpose (in a child process),
# and on the H100 (driver 580) graphics submissions made after that never complete.
[[ -x $CUDA_TESTS ]] && run_step 150 "$OUT/cuda_tests.log" "$CUDA_TESTS"
# Again with a grid of at most 3 blocks per launch, so every kernel's grid-stride loop runs.
[[ -x $CUDA_TESTS ]] && run_step 150 "$OUT/cuda_tests.log" env HMSM_CUDA_MAX_BLOCKS=3 "$CUDA_TESTS" \
    --gtest_filter='-CudaErrors*'

# --- compute-sanitizer over the CUDA suite ---------------------------------------------
if [[ -x $CUDA_TESTS ]] && command -v compute-sanitizer >/dev/null; then
    for tool in memcheck initcheck synccheck; do
        extra=()
        [[ $tool == memcheck ]] && extra=(--leak-check full)
        run_step 60 "$OUT/sanitizers.log" compute-sanitizer --tool "$tool" "${extra[@]}" \
            --error-exitcode 99 "$CUDA_TESTS" --gtest_filter="$SANITIZER_FILTER" --gtest_brief=1
    done
    # racecheck is far slower per launch (over 240 s for the whole suite): every kernel in both
    # compositions, the graph path and interop are enough for it (no kernel uses shared memory).
    run_step 200 "$OUT/sanitizers.log" compute-sanitizer --tool racecheck --error-exitcode 99 \
        "$CUDA_TESTS" --gtest_filter='CudaInterop.*:CudaProfiling.*'
    [[ -x $CORE_TESTS ]] && run_step 200 "$OUT/sanitizers.log" compute-sanitizer --tool racecheck \
        --error-exitcode 99 "$CORE_TESTS" --gtest_filter='Backends/PassAgreement.*/cuda_*:-*cuda_emulation*'
    grep -E '^\[ +(OK|FAILED) +\]' "$OUT/sanitizers.log" | tail -30 >>"$SUMMARY"
fi

# --- CLI (HMSM_GPU_CLI=0 leaves it to tools/bench_gpu.sh in a second call) ---------------
if [[ -x $CLI && ${HMSM_GPU_CLI:-1} != 0 ]]; then
    run_step 60 "$OUT/cli.log" "$CLI" simulate --preset paper-1 --backend cuda --steps 240 \
        --dump-nodes "$OUT/nodes_cuda.csv" --report "$OUT/report_cuda.json"
    # A forest of 10,000 paper-1 trees (7.9e8 mesh vertices, about 31 GB on the device).
    run_step 120 "$OUT/cli.log" "$CLI" simulate --preset paper-1 --instances 10000 --spacing 15 \
        --backend cuda --steps 10
    [[ -x $BUILD/hmsm_cuda_throughput ]] && run_step 150 "$OUT/cli.log" "$BUILD/hmsm_cuda_throughput"
    if "$CLI" --help 2>&1 | grep -qE '^ +bench'; then
        run_step 240 "$OUT/cli.log" "$CLI" bench --backends cpu,vulkan,cuda --case-budget 5 \
            --no-progress --json "$OUT/bench.json"
    fi
    rm -f "$OUT/nodes_cuda.csv"
fi

# --- summary ---------------------------------------------------------------------------
{
    echo "== test results"
    for log in cuda_tests core_tests vulkan_tests; do
        [[ -f $OUT/$log.log ]] && grep -HE '^\[==========\] .* ran|^\[  PASSED  \] [0-9]|^\[  SKIPPED \] [0-9]|^\[  FAILED  \]' "$OUT/$log.log" | head -40
    done
    echo "== sanitizers"
    [[ -f $OUT/sanitizers.log ]] && grep -E '^### |ERROR SUMMARY|LEAK SUMMARY|RACECHECK SUMMARY|Target application returned' "$OUT/sanitizers.log"
    echo "== throughput"
    [[ -f $OUT/cli.log ]] && sed -n '/hmsm_cuda_throughput/,/^###/p' "$OUT/cli.log"
    echo "== report"
    [[ -f $OUT/report_cuda.json ]] && tr -d ' \n' <"$OUT/report_cuda.json" && echo
} >>"$SUMMARY" 2>&1
echo "----- summary -----"
cat "$SUMMARY"
