// Pass 3: total rotation R_c = R_parent T_c, accumulated down the chain tree.
// Pointer jumping (the paper's M_temp): round r replaces each chain's partial product P by
// P(2^r-th ancestor) P, reading half src_half of chain_rotation and writing half dst_half
// (round 0 starts from T), so after ceil(log2(D+1)) rounds P is the full product. In-dispatch
// mode runs every round in one launch, one block per instance, __syncthreads() between rounds.
// Level by level: one depth per dispatch, R = R_parent T in place in the pose half (dst_half),
// the parent having been written by the previous dispatch.
#include "pass_math.cuh"

namespace hmsm::detail::cuda {

/// One pointer-jumping round for model chain c of group instance k. kWrittenInBlock: the src
/// half was written by this block's previous round (in-dispatch mode).
template <bool kWrittenInBlock>
static HMSM_HOST_DEVICE void compose_jump(const BufferPointers& b, const gpu::PassConstants& pc,
                                          uint32_t k, uint32_t c, uint32_t round,
                                          uint32_t src_half, uint32_t dst_half) {
    const uint64_t chain = state_chain(pc, k, int32_t(c));
    const int32_t ancestor =
        load(b.chain_jump + uint64_t(round) * pc.total_model_chains + pc.model_chain_begin + c);
    // The product accumulated so far: T itself before round 0, else the src half.
    auto product_so_far = [&](uint64_t state) {
        if (round == 0) return load_mat3(b.chain_local, state);
        const uint64_t at = half_begin(pc, src_half) + state;
        return kWrittenInBlock ? load_mat3_written_in_block(b.chain_rotation, at)
                               : load_mat3(b.chain_rotation, at);
    };
    Mat3 rotation = product_so_far(chain);
    if (ancestor >= 0) rotation = product_so_far(state_chain(pc, k, ancestor)) * rotation;
    store_mat3(b.chain_rotation, half_begin(pc, dst_half) + chain, rotation);
}

static HMSM_HOST_DEVICE void compose_element(const BufferPointers& b,
                                             const gpu::PassConstants& pc, uint32_t i) {
    if (pc.mode == HMSM_MODE_LEVEL_BY_LEVEL) {
        const LevelChain l = level_chain(b, pc, i);
        Mat3 rotation = load_mat3(b.chain_local, l.chain);
        if (l.parent >= 0)
            rotation = load_mat3(b.chain_rotation, l.dst + state_chain(pc, l.instance, l.parent)) * rotation;
        store_mat3(b.chain_rotation, l.dst + l.chain, rotation);
        return;
    }
    const Element e = element_of(i, pc.model_chain_count);
    compose_jump<false>(b, pc, e.instance, e.index, pc.round, pc.src_half, pc.dst_half);
}

HMSM_CUDA_ROUNDS_PASS(compose)

}  // namespace hmsm::detail::cuda
