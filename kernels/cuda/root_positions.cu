// Pass 5: chain origins O_c = O_parent + u_attach(c), O_trunk = the instance origin, summed down
// the chain tree like compose (the paper's Root Positions temporary). Pointer jumping: round r
// adds the partial sum of the 2^r-th ancestor, src_half -> dst_half, round 0 starting from each
// chain's own offset; in-dispatch mode runs every round in one launch, one block per instance.
// Level by level: one depth per dispatch, in place in dst_half.
// Wherever O_c is written, the joint matrix [R_c | O_c] is written too, R_c from the same half
// (compose left the final R there): level by level and the last in-dispatch round write final
// values once; per-round launches write in every round and the last round (the final half)
// leaves the final matrices.
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

/// Joint matrix of state chain `chain` (gpu_layout.h): rows (R row i, O_i), R from `pose_half`.
static HMSM_HOST_DEVICE void store_joint(const BufferPointers& b, const gpu::PassConstants& pc,
                                         uint64_t chain, uint32_t pose_half, float4 o) {
    const Mat3 r = load_mat3(b.chain_rotation, half_begin(pc, pose_half) + chain);
    float4* row = b.joint_matrix + 3 * chain;
    row[0] = make_float4(r.c0.x, r.c1.x, r.c2.x, o.x);
    row[1] = make_float4(r.c0.y, r.c1.y, r.c2.y, o.y);
    row[2] = make_float4(r.c0.z, r.c1.z, r.c2.z, o.z);
}

/// One pointer-jumping round for model chain c of group instance k. kWrittenInBlock: the src
/// half was written by this block's previous round (in-dispatch mode). The joint matrix is
/// written in the last round of an in-dispatch run, and in every round of a per-round run (a
/// dispatch cannot tell it is the last; the final round's write is the one that stays).
template <bool kWrittenInBlock>
static HMSM_HOST_DEVICE void root_positions_jump(const BufferPointers& b,
                                                 const gpu::PassConstants& pc, uint32_t k,
                                                 int32_t c, uint32_t round, uint32_t src_half,
                                                 uint32_t dst_half) {
    const bool write_joint = pc.mode != HMSM_MODE_POINTER_JUMPING_IN_DISPATCH || round + 1 == pc.round;
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
    if (write_joint) store_joint(b, pc, state_chain(pc, k, c), dst_half, origin);
}

static HMSM_HOST_DEVICE void root_positions_element(const BufferPointers& b,
                                                    const gpu::PassConstants& pc, uint32_t i) {
    if (pc.mode == HMSM_MODE_LEVEL_BY_LEVEL) {
        const LevelChain l = level_chain(b, pc, i);
        float4 origin = own_offset(b, pc, l.instance, l.c);
        if (l.parent >= 0) origin = origin + load(b.chain_origin + l.dst + state_chain(pc, l.instance, l.parent));
        b.chain_origin[l.dst + l.chain] = origin;
        store_joint(b, pc, l.chain, pc.dst_half, origin);
        return;
    }
    const Element e = element_of(i, pc.model_chain_count);
    root_positions_jump<false>(b, pc, e.instance, int32_t(e.index), pc.round, pc.src_half, pc.dst_half);
}

HMSM_CUDA_ROUNDS_PASS(root_positions)

}  // namespace hmsm::detail::cuda
