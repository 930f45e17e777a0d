// Pass 4: each node's position relative to its chain's origin, u_n = R_owner l_n (the pose half
// src_half of chain_rotation holds R).
#include "pass_math.cuh"

namespace hmsm::detail::cuda {

static HMSM_HOST_DEVICE void node_relative_element(const BufferPointers& b,
                                                   const gpu::PassConstants& pc, uint32_t i) {
    const Element e = element_of(i, pc.model_node_count);
    if (instance_paused(b, pc, e.instance)) return;
    const uint32_t model_node = pc.model_node_begin + e.index;
    const int32_t owner = load(b.node_owner + model_node);
    const float3 local = xyz(load(b.node_local + model_node));
    // The node pair (path walk): node_world follows in the same launch (node_world.cu) with u in hand, which is
    // not stored, and the pose is the joint matrix (pass_table.h walk_reads, walk_writes).
    if (pc.kind == HMSM_DISPATCH_NODE_PAIR) {
        const Pose pose = load_joint(b, state_chain(pc, e.instance, owner));
        b.node_world[pc.node_begin + i] = with_w(pose.origin + pose.rotation * local, 1.0f);
        return;
    }
    const Mat3 rotation =
        load_mat3(b.chain_rotation, half_begin(pc, pc.src_half) + state_chain(pc, e.instance, owner));
    b.node_relative[pc.node_begin + i] = with_w(rotation * local, 0.0f);
}

HMSM_CUDA_PASS(node_relative)

}  // namespace hmsm::detail::cuda
