// Pass 6: world positions W_n = O_owner + u_n.
#include "cpu_state.h"

namespace hmsm::detail::cpu {

template <class T>
void node_world(State<T>& s, const gpu::PassConstants& pc, Range r) {
    const uint64_t pose = uint64_t(pc.src_half) * s.total_chains;
    for (uint32_t i = r.begin; i < r.end; ++i) {
        Element e = element_of(i, pc.model_node_count);
        if (instance_paused(s, pc, e.instance)) continue;
        int32_t owner = s.node_owner[pc.model_node_begin + e.index];
        uint64_t n = state_node(pc, e.instance, int32_t(e.index));
        auto w = s.chain_origin[pose + state_chain(pc, e.instance, owner)] + s.node_relative[n];
        s.node_world[n] = {w.x, w.y, w.z, T(1)};
    }
}

template void node_world<float>(State<float>&, const gpu::PassConstants&, Range);
template void node_world<double>(State<double>&, const gpu::PassConstants&, Range);

}  // namespace hmsm::detail::cpu
