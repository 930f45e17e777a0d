#include "launch_dispatch.h"

#include <cstdlib>
#include <string_view>

namespace hmsm::detail::cuda {

bool programmatic_launch_enabled() {
    static const bool enabled = [] {
        const char* value = std::getenv("HMSM_CUDA_PROGRAMMATIC_LAUNCH");
        return !(value && std::string_view(value) == "0");
    }();
    return enabled;
}

uint32_t max_launch_blocks() {
    static const uint32_t blocks = [] {
        const char* value = std::getenv("HMSM_CUDA_MAX_BLOCKS");
        const unsigned long parsed = value ? std::strtoul(value, nullptr, 10) : 0;
        return parsed >= 1 && parsed <= (1ul << 24) ? uint32_t(parsed) : uint32_t(1) << 16;
    }();
    return blocks;
}

// The wind-table slot of the step reaches the dispatches that read it through their constants
// (Backend::run).
static gpu::PassConstants step_constants(const Dispatch& dispatch, uint32_t wind_slot) {
    gpu::PassConstants pc = dispatch.constants;
    if (reads_wind_slot(dispatch)) pc.wind_slot = wind_slot;
    return pc;
}

cudaError_t launch_dispatch(const Dispatch& dispatch, const BufferPointers& buffers, uint32_t wind_slot,
                            cudaStream_t stream) {
    const gpu::PassConstants pc = step_constants(dispatch, wind_slot);
    switch (dispatch.pass) {
#define HMSM_CUDA_LAUNCH_CASE(name) \
    case Pass::name: return launch_##name(buffers, pc, stream);
        HMSM_PASSES(HMSM_CUDA_LAUNCH_CASE)
#undef HMSM_CUDA_LAUNCH_CASE
    }
    return cudaErrorInvalidValue;
}

void emulate_dispatch(const Dispatch& dispatch, const BufferPointers& host_buffers, uint32_t wind_slot) {
    const gpu::PassConstants pc = step_constants(dispatch, wind_slot);
    switch (dispatch.pass) {
#define HMSM_CUDA_EMULATE_CASE(name) \
    case Pass::name: emulate_##name(host_buffers, pc); return;
        HMSM_PASSES(HMSM_CUDA_EMULATE_CASE)
#undef HMSM_CUDA_EMULATE_CASE
    }
}

cudaError_t launch_batch(Pass pass, const BufferPointers& buffers, const BatchLaunch& batch,
                         const BatchShape& shape, cudaStream_t stream) {
    switch (pass) {
#define HMSM_CUDA_LAUNCH_BATCH_CASE(name) \
    case Pass::name: return launch_batch_##name(buffers, batch, shape, stream);
        HMSM_PASSES(HMSM_CUDA_LAUNCH_BATCH_CASE)
#undef HMSM_CUDA_LAUNCH_BATCH_CASE
    }
    return cudaErrorInvalidValue;
}

void emulate_batch(Pass pass, const BufferPointers& host_buffers, const BatchLaunch& batch, const BatchShape& shape) {
    switch (pass) {
#define HMSM_CUDA_EMULATE_BATCH_CASE(name) \
    case Pass::name: emulate_batch_##name(host_buffers, batch, shape); return;
        HMSM_PASSES(HMSM_CUDA_EMULATE_BATCH_CASE)
#undef HMSM_CUDA_EMULATE_BATCH_CASE
    }
}

}  // namespace hmsm::detail::cuda
