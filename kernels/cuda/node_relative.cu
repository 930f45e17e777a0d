// Pass 4: each node's position relative to its chain's origin, u_n = R_owner l_n (the pose half
// src_half of chain_rotation holds R).
#include "pass_math.cuh"

namespace hmsm::detail::cuda {

static HMSM_HOST_DEVICE void node_relative_element(const BufferPointers& b,
                                                   const gpu::PassConstants& pc, uint32_t i) {
    const Element e = element_of(i, pc.model_node_count);
    const uint32_t model_node = pc.model_node_begin + e.index;
    const int32_t owner = load(b.node_owner + model_node);
    const float3 local = xyz(load(b.node_local + model_node));
    const Mat3 rotation =
        load_mat3(b.chain_rotation, half_begin(pc, pc.src_half) + state_chain(pc, e.instance, owner));
    b.node_relative[pc.node_begin + i] = with_w(rotation * local, 0.0f);
}

static __global__ void __launch_bounds__(HMSM_WORKGROUP_SIZE)
    node_relative_kernel(const BufferPointers b, const gpu::PassConstants pc) {
    begin_pass();
    for (uint32_t i = blockIdx.x * blockDim.x + threadIdx.x; i < pc.element_count;
         i += gridDim.x * blockDim.x)
        node_relative_element(b, pc, i);
}

cudaError_t launch_node_relative(const BufferPointers& b, const gpu::PassConstants& pc,
                                 cudaStream_t stream) {
    if (pc.element_count == 0) return cudaSuccess;
    return launch_pass(node_relative_kernel, launch_blocks(pc.element_count), HMSM_WORKGROUP_SIZE, stream, b, pc);
}

void emulate_node_relative(const BufferPointers& b, const gpu::PassConstants& pc) {
    for (uint32_t i = 0; i < pc.element_count; ++i) node_relative_element(b, pc, i);
}

}  // namespace hmsm::detail::cuda
