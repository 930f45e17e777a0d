// Pass 3: total rotation R_c = R_parent T_c. Pointer jumping: round r multiplies in the product
// held by the 2^r-th ancestor, reading one half of chain_rotation and writing the other (round 0
// reads T); in-dispatch mode runs every round in turn. Level by level: one depth per dispatch,
// in place in the pose half.
#include "cpu_state.h"

namespace hmsm::detail::cpu {
namespace {

template <class T>
void compose_round(State<T>& s, const gpu::PassConstants& pc, uint32_t round, uint32_t src_half,
                   uint32_t dst_half, Range r) {
    const uint64_t src = uint64_t(src_half) * s.total_chains;
    const uint64_t dst = uint64_t(dst_half) * s.total_chains;
    auto product_so_far = [&](uint64_t gc) -> const auto& {
        return round == 0 ? s.chain_local[gc] : s.chain_rotation[src + gc];
    };
    for (uint32_t i = r.begin; i < r.end; ++i) {
        Element e = element_of(i, pc.model_chain_count);
        if (instance_paused(s, pc, e.instance)) continue;
        uint64_t gc = state_chain(pc, e.instance, int32_t(e.index));
        int32_t ancestor =
            s.chain_jump[uint64_t(round) * pc.total_model_chains + pc.model_chain_begin + e.index];
        s.chain_rotation[dst + gc] =
            ancestor < 0 ? product_so_far(gc)
                         : product_so_far(state_chain(pc, e.instance, ancestor)) * product_so_far(gc);
    }
}

}  // namespace

template <class T>
void compose(State<T>& s, const gpu::PassConstants& pc, Range r) {
    // Level by level: R = R_parent T in place in the pose half.
    auto level = [&](uint64_t dst, uint32_t k, int32_t c, int32_t parent) {
        const uint64_t gc = state_chain(pc, k, c);
        s.chain_rotation[dst + gc] =
            parent < 0 ? s.chain_local[gc]
                       : s.chain_rotation[dst + state_chain(pc, k, parent)] * s.chain_local[gc];
    };
    auto round = [&](uint32_t rd, uint32_t src_half, uint32_t dst_half, Range chains, bool) {
        compose_round(s, pc, rd, src_half, dst_half, chains);
    };
    run_hierarchical(s, pc, r, level, round);
}

template void compose<float>(State<float>&, const gpu::PassConstants&, Range);
template void compose<double>(State<double>&, const gpu::PassConstants&, Range);

}  // namespace hmsm::detail::cpu
