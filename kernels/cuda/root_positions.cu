// Pass 5: chain origins O_c = O_parent + u_attach(c), O_trunk = the instance origin, summed down
// the chain tree like compose (the paper's Root Positions temporary). Pointer jumping: round r
// adds the partial sum of the 2^r-th ancestor, src_half -> dst_half, round 0 starting from each
// chain's own offset; in-dispatch mode runs every round in one launch, one block per instance.
// Level by level: one depth per dispatch, in place in dst_half.
#include "pass_math.cuh"

namespace hmsm::detail::cuda {

/// What chain c of group instance k contributes on its own: the instance origin for the trunk,
/// else its attach node's position relative to the parent chain's origin.
static HMSM_HOST_DEVICE float4 own_offset(const BufferPointers& b, const gpu::PassConstants& pc,
                                          uint32_t k, int32_t c) {
    if (load(b.chain_parent + pc.model_chain_begin + c) < 0) {
        const float4 origin = load(b.instance_origin + pc.instance_begin + k);
        return make_float4(origin.x, origin.y, origin.z, 0.0f);
    }
    return load(b.node_relative + state_node(pc, k, load(b.chain_attach + pc.model_chain_begin + c)));
}

/// One pointer-jumping round for model chain c of group instance k. kWrittenInBlock: the src
/// half was written by this block's previous round (in-dispatch mode).
template <bool kWrittenInBlock>
static HMSM_HOST_DEVICE void root_positions_jump(const BufferPointers& b,
                                                 const gpu::PassConstants& pc, uint32_t k,
                                                 int32_t c, uint32_t round, uint32_t src_half,
                                                 uint32_t dst_half) {
    const int32_t ancestor =
        load(b.chain_jump + uint64_t(round) * pc.total_model_chains + pc.model_chain_begin + c);
    const uint64_t src = half_begin(pc, src_half);
    auto sum_so_far = [&](int32_t chain) {
        if (round == 0) return own_offset(b, pc, k, chain);
        const float4* at = b.chain_origin + src + state_chain(pc, k, chain);
        return kWrittenInBlock ? *at : load(at);
    };
    float4 origin = sum_so_far(c);
    if (ancestor >= 0) origin = origin + sum_so_far(ancestor);
    b.chain_origin[half_begin(pc, dst_half) + state_chain(pc, k, c)] = origin;
}

static HMSM_HOST_DEVICE void root_positions_element(const BufferPointers& b,
                                                    const gpu::PassConstants& pc, uint32_t i) {
    if (pc.mode == HMSM_MODE_LEVEL_BY_LEVEL) {
        const uint64_t dst = half_begin(pc, pc.dst_half);
        const Element e = element_of(i, pc.level_count);
        const int32_t c = int32_t(pc.level_begin + e.index);
        const int32_t parent = load(b.chain_parent + pc.model_chain_begin + c);
        float4 origin = own_offset(b, pc, e.instance, c);
        if (parent >= 0) origin = origin + load(b.chain_origin + dst + state_chain(pc, e.instance, parent));
        b.chain_origin[dst + state_chain(pc, e.instance, c)] = origin;
        return;
    }
    const Element e = element_of(i, pc.model_chain_count);
    root_positions_jump<false>(b, pc, e.instance, int32_t(e.index), pc.round, pc.src_half, pc.dst_half);
}

HMSM_CUDA_ROUNDS_PASS(root_positions)

}  // namespace hmsm::detail::cuda
