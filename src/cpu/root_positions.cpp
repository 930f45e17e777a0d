// Pass 5: chain origins O_c = O_parent + u_attach(c), O_trunk = instance origin. Pointer jumping
// adds the partial sum held by the 2^r-th ancestor (round 0 starts from u at the attach node);
// in-dispatch mode runs every round in turn. Level by level: one depth per dispatch, in place
// in the pose half. Wherever a dispatch writes O_c it also writes the joint matrix [R_c | O_c]
// (R_c from the same half, which compose left final): level by level and the in-dispatch last
// round write final values once; per-round dispatches write in every round and the last round,
// whose half is the final one, leaves the final matrices.
#include "cpu_state.h"

namespace hmsm::detail::cpu {
namespace {

/// The offset a chain contributes on its own: the instance origin for the trunk, else the
/// attach node's position relative to the parent chain's origin.
template <class T>
typename State<T>::vec4 own_offset(const State<T>& s, const gpu::PassConstants& pc, uint32_t k,
                                   int32_t c) {
    if (s.chain_parent[pc.model_chain_begin + c] < 0) {
        const auto& o = s.instance_origin[pc.instance_begin + k];
        return {o.x, o.y, o.z, T(0)};
    }
    return s.node_relative[state_node(pc, k, s.chain_attach[pc.model_chain_begin + c])];
}

template <class T>
void root_positions_round(State<T>& s, const gpu::PassConstants& pc, uint32_t round, uint32_t src_half,
                          uint32_t dst_half, Range r, bool write_joints) {
    using vec4 = typename State<T>::vec4;
    const uint64_t src = uint64_t(src_half) * s.total_chains;
    const uint64_t dst = uint64_t(dst_half) * s.total_chains;
    auto sum_so_far = [&](uint32_t k, int32_t c) -> vec4 {
        return round == 0 ? own_offset(s, pc, k, c) : s.chain_origin[src + state_chain(pc, k, c)];
    };
    for (uint32_t i = r.begin; i < r.end; ++i) {
        Element e = element_of(i, pc.model_chain_count);
        if (instance_paused(s, pc, e.instance)) continue;
        int32_t c = int32_t(e.index);
        int32_t ancestor =
            s.chain_jump[uint64_t(round) * pc.total_model_chains + pc.model_chain_begin + c];
        vec4 origin = sum_so_far(e.instance, c);
        if (ancestor >= 0) origin += sum_so_far(e.instance, ancestor);
        const uint64_t chain = state_chain(pc, e.instance, c);
        s.chain_origin[dst + chain] = origin;
        if (write_joints) store_joint(s, chain, s.chain_rotation[dst + chain], origin);
    }
}

}  // namespace

template <class T>
void root_positions(State<T>& s, const gpu::PassConstants& pc, Range r) {
    using vec4 = typename State<T>::vec4;
    // Level by level: O_c = O_parent + own offset in place in the pose half, with the joint.
    auto level = [&](uint64_t dst, uint32_t k, int32_t c, int32_t parent) {
        vec4 origin = own_offset(s, pc, k, c);
        if (parent >= 0) origin += s.chain_origin[dst + state_chain(pc, k, parent)];
        const uint64_t chain = state_chain(pc, k, c);
        s.chain_origin[dst + chain] = origin;
        store_joint(s, chain, s.chain_rotation[dst + chain], origin);
    };
    // In one dispatch only the last round writes the joint matrices.
    auto round = [&](uint32_t rd, uint32_t src_half, uint32_t dst_half, Range chains, bool last) {
        root_positions_round(s, pc, rd, src_half, dst_half, chains, last);
    };
    run_hierarchical(s, pc, r, level, round);
}

template void root_positions<float>(State<float>&, const gpu::PassConstants&, Range);
template void root_positions<double>(State<double>&, const gpu::PassConstants&, Range);

}  // namespace hmsm::detail::cpu
