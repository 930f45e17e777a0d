// Pass 3: total rotation R_c = R_parent T_c, accumulated down the chain tree.
// Pointer jumping (the paper's M_temp): round r replaces each chain's partial product P by
// P(2^r-th ancestor) P, reading half src_half of chain_rotation and writing half dst_half
// (round 0 starts from T), so after ceil(log2(D+1)) rounds P is the full product. Level by
// level: one depth per dispatch, R = R_parent T in place in the pose half (dst_half), the
// parent having been written by the previous dispatch.
#include "pass_math.cuh"

namespace hmsm::detail::cuda {

static HMSM_HOST_DEVICE void compose_element(const BufferPointers& b,
                                             const gpu::PassConstants& pc, uint32_t i) {
    const uint64_t dst = half_begin(pc, pc.dst_half);
    if (pc.mode == HMSM_MODE_LEVEL_BY_LEVEL) {
        const Element e = element_of(i, pc.level_count);
        const int32_t c = int32_t(pc.level_begin + e.index);
        const int32_t parent = load(b.chain_parent + pc.model_chain_begin + c);
        const uint64_t chain = state_chain(pc, e.instance, c);
        Mat3 rotation = load_mat3(b.chain_local, chain);
        if (parent >= 0)
            rotation = load_mat3(b.chain_rotation, dst + state_chain(pc, e.instance, parent)) * rotation;
        store_mat3(b.chain_rotation, dst + chain, rotation);
        return;
    }
    const Element e = element_of(i, pc.model_chain_count);
    const uint64_t chain = pc.chain_begin + i;
    const int32_t ancestor =
        load(b.chain_jump + uint64_t(pc.round) * pc.total_model_chains + pc.model_chain_begin + e.index);
    // The product accumulated so far: T itself before round 0, else the src half.
    const float4* product = pc.round == 0 ? b.chain_local : b.chain_rotation;
    const uint64_t src = pc.round == 0 ? 0 : half_begin(pc, pc.src_half);
    Mat3 rotation = load_mat3(product, src + chain);
    if (ancestor >= 0)
        rotation = load_mat3(product, src + state_chain(pc, e.instance, ancestor)) * rotation;
    store_mat3(b.chain_rotation, dst + chain, rotation);
}

static __global__ void __launch_bounds__(HMSM_WORKGROUP_SIZE)
    compose_kernel(const BufferPointers b, const gpu::PassConstants pc) {
    for (uint32_t i = blockIdx.x * blockDim.x + threadIdx.x; i < pc.element_count;
         i += gridDim.x * blockDim.x)
        compose_element(b, pc, i);
}

cudaError_t launch_compose(const BufferPointers& b, const gpu::PassConstants& pc,
                           cudaStream_t stream) {
    if (pc.element_count == 0) return cudaSuccess;
    compose_kernel<<<launch_blocks(pc.element_count), HMSM_WORKGROUP_SIZE, 0, stream>>>(b, pc);
    return cudaGetLastError();
}

void emulate_compose(const BufferPointers& b, const gpu::PassConstants& pc) {
    for (uint32_t i = 0; i < pc.element_count; ++i) compose_element(b, pc, i);
}

}  // namespace hmsm::detail::cuda
