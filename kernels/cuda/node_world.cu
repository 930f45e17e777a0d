// Pass 6: world positions W_n = O_owner + u_n (the pose half src_half of chain_origin holds O).
#include "pass_math.cuh"

namespace hmsm::detail::cuda {

static HMSM_HOST_DEVICE void node_world_element(const BufferPointers& b,
                                                const gpu::PassConstants& pc, uint32_t i) {
    const Element e = element_of(i, pc.model_node_count);
    if (instance_paused(b, pc, e.instance)) return;
    const int32_t owner = load(b.node_owner + pc.model_node_begin + e.index);
    const uint64_t node = pc.node_begin + i;
    const float4 origin =
        load(b.chain_origin + half_begin(pc, pc.src_half) + state_chain(pc, e.instance, owner));
    const float4 relative = load(b.node_relative + node);
    b.node_world[node] = with_w(xyz(origin) + xyz(relative), 1.0f);
}

HMSM_CUDA_PASS(node_world)

}  // namespace hmsm::detail::cuda
