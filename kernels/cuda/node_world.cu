// Pass 6: world positions W_n = O_owner + u_n (the pose half src_half of chain_origin holds O).
#include "pass_math.cuh"

namespace hmsm::detail::cuda {

static HMSM_HOST_DEVICE void node_world_element(const BufferPointers& b,
                                                const gpu::PassConstants& pc, uint32_t i) {
    const Element e = element_of(i, pc.model_node_count);
    const int32_t owner = load(b.node_owner + pc.model_node_begin + e.index);
    const uint64_t node = pc.node_begin + i;
    const float4 origin =
        load(b.chain_origin + half_begin(pc, pc.src_half) + state_chain(pc, e.instance, owner));
    const float4 relative = load(b.node_relative + node);
    b.node_world[node] = with_w(xyz(origin) + xyz(relative), 1.0f);
}

static __global__ void __launch_bounds__(HMSM_WORKGROUP_SIZE)
    node_world_kernel(const BufferPointers b, const gpu::PassConstants pc) {
    begin_pass();
    for (uint32_t i = blockIdx.x * blockDim.x + threadIdx.x; i < pc.element_count;
         i += gridDim.x * blockDim.x)
        node_world_element(b, pc, i);
}

cudaError_t launch_node_world(const BufferPointers& b, const gpu::PassConstants& pc,
                              cudaStream_t stream) {
    if (pc.element_count == 0) return cudaSuccess;
    return launch_pass(node_world_kernel, launch_blocks(pc.element_count), HMSM_WORKGROUP_SIZE, stream, b, pc);
}

void emulate_node_world(const BufferPointers& b, const gpu::PassConstants& pc) {
    for (uint32_t i = 0; i < pc.element_count; ++i) node_world_element(b, pc, i);
}

}  // namespace hmsm::detail::cuda
