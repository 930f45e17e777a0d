// Pass 5: chain origins O_c = O_parent + u_attach(c), O_trunk = the instance origin, summed down
// the chain tree like compose (the paper's Root Positions temporary). Pointer jumping: round r
// adds the partial sum of the 2^r-th ancestor, src_half -> dst_half, round 0 starting from each
// chain's own offset (root_jump, chain_math.cuh); JUMP_ROUNDS_IN_DISPATCH runs every round in
// one launch, one block per instance. LEVEL: one depth per dispatch, in place in dst_half.
// Wherever O_c is written, the joint matrix [R_c | O_c] is written too, R_c from the same half
// (compose left the final R there): level by level and the last in-dispatch round write final
// values once; per-round launches write in every round and the last round (the final half)
// leaves the final matrices.
#include "chain_math.cuh"

namespace hmsm::detail::cuda {

/// One pointer-jumping round for model chain c of group instance k. kWrittenInBlock: the src
/// half was written by this block's previous round (JUMP_ROUNDS_IN_DISPATCH). The joint matrix is
/// written in the last round of an in-dispatch run, and in every round of a per-round run (a
/// dispatch cannot tell it is the last; the final round's write is the one that stays).
template <bool kWrittenInBlock>
static HMSM_HOST_DEVICE void root_positions_jump(const BufferPointers& b,
                                                 const gpu::PassConstants& pc, uint32_t k,
                                                 int32_t c, uint32_t round, uint32_t src_half,
                                                 uint32_t dst_half) {
    const bool write_joint = pc.kind != HMSM_DISPATCH_JUMP_ROUNDS_IN_DISPATCH || round + 1 == pc.round;
    root_jump<kWrittenInBlock>(b, pc, k, c, round, src_half, dst_half, write_joint);
}

static HMSM_HOST_DEVICE void root_positions_element(const BufferPointers& b,
                                                    const gpu::PassConstants& pc, uint32_t i) {
    if (pc.kind == HMSM_DISPATCH_LEVEL) {
        const LevelChain l = level_chain(b, pc, i);
        if (instance_paused(b, pc, l.instance)) return;
        float4 origin = own_offset(b, pc, l.instance, l.c);
        if (l.parent >= 0) origin = origin + load(b.chain_origin + l.dst + state_chain(pc, l.instance, l.parent));
        b.chain_origin[l.dst + l.chain] = origin;
        store_joint(b, pc, l.chain, pc.dst_half, origin);
        return;
    }
    const Element e = element_of(i, pc.model_chain_count);
    if (instance_paused(b, pc, e.instance)) return;
    root_positions_jump<false>(b, pc, e.instance, int32_t(e.index), pc.round, pc.src_half, pc.dst_half);
}

HMSM_CUDA_ROUNDS_PASS(root_positions)

}  // namespace hmsm::detail::cuda
