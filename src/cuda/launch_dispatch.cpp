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

cudaError_t launch_dispatch(const Dispatch& dispatch, const BufferPointers& buffers, float wind_x,
                            cudaStream_t stream) {
    gpu::PassConstants pc = dispatch.constants;
    switch (dispatch.pass) {
        case Pass::wind_force: pc.wind.w = wind_x; return launch_wind_force(buffers, pc, stream);
        case Pass::integrate: return launch_integrate(buffers, pc, stream);
        case Pass::compose: return launch_compose(buffers, pc, stream);
        case Pass::node_relative: return launch_node_relative(buffers, pc, stream);
        case Pass::root_positions: return launch_root_positions(buffers, pc, stream);
        case Pass::node_world: return launch_node_world(buffers, pc, stream);
        case Pass::contour: return launch_contour(buffers, pc, stream);
    }
    return cudaErrorInvalidValue;
}

void emulate_dispatch(const Dispatch& dispatch, const BufferPointers& host_buffers, float wind_x) {
    gpu::PassConstants pc = dispatch.constants;
    switch (dispatch.pass) {
        case Pass::wind_force: pc.wind.w = wind_x; emulate_wind_force(host_buffers, pc); return;
        case Pass::integrate: emulate_integrate(host_buffers, pc); return;
        case Pass::compose: emulate_compose(host_buffers, pc); return;
        case Pass::node_relative: emulate_node_relative(host_buffers, pc); return;
        case Pass::root_positions: emulate_root_positions(host_buffers, pc); return;
        case Pass::node_world: emulate_node_world(host_buffers, pc); return;
        case Pass::contour: emulate_contour(host_buffers, pc); return;
    }
}

}  // namespace hmsm::detail::cuda
