// The thread -> element mapping of a dispatch (gpu_layout.h, PassConstants), shared by the CPU
// passes and the CUDA kernels: thread i of a dispatch over an instance group handles model
// element i % per_instance of group instance i / per_instance, whose state lies at the group's
// first state element + instance x the model's count + element (a listed dispatch's instances
// are rebased one by one first: listed_instance_constants).
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

/// The constants of a listed dispatch (gpu_layout.h PassConstants.instance_list) for one of its
/// instances, whose instance-table entry is `entry` (chain_begin, node_begin, vertex_begin,
/// instance): a dispatch over that instance alone, whose threads are the instance's elements
/// (thread i of the listed dispatch is thread i % listed_threads of instance i / listed_threads).
/// A list holds active instances only, so the result skips none.
template <class Entry>
HMSM_HOST_DEVICE gpu::PassConstants listed_instance_constants(gpu::PassConstants pc, const Entry& entry) {
    pc.chain_begin = uint32_t(entry.x);
    pc.node_begin = uint32_t(entry.y);
    pc.vertex_begin = uint32_t(entry.z);
    pc.instance_begin = uint32_t(entry.w);
    pc.element_count = pc.listed_threads;
    pc.instance_list = 0;
    pc.params.w = 0.0f;
    return pc;
}

}  // namespace hmsm::detail
