// The thread -> element mapping of a dispatch (gpu_layout.h, PassConstants), shared by the CPU
// passes and the CUDA kernels: thread i of a dispatch over an instance group handles model
// element i % per_instance of group instance i / per_instance, whose state lies at the group's
// first state element + instance x the model's count + element.
#pragma once

#include "gpu_layout.h"
#include "host_device.h"

#include <cstdint>

namespace hmsm::detail {

/// Which instance of the group and which model element a thread of a dispatch handles.
struct Element {
    uint32_t instance;  ///< index within the group
    uint32_t index;     ///< model-local chain, node or vertex
};
HMSM_HOST_DEVICE Element element_of(uint32_t i, uint32_t per_instance) {
    return {i / per_instance, i % per_instance};
}
/// State index of model chain `c` of group instance `k` (one ping-pong half).
HMSM_HOST_DEVICE uint64_t state_chain(const gpu::PassConstants& pc, uint32_t k, int32_t c) {
    return pc.chain_begin + uint64_t(k) * pc.model_chain_count + uint64_t(c);
}
/// State index of model node `n` of group instance `k`.
HMSM_HOST_DEVICE uint64_t state_node(const gpu::PassConstants& pc, uint32_t k, int32_t n) {
    return pc.node_begin + uint64_t(k) * pc.model_node_count + uint64_t(n);
}

}  // namespace hmsm::detail
