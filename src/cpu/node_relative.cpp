// Pass 4: each node's position relative to its chain's origin, u_n = R_owner l_n.
#include "cpu_state.h"

namespace hmsm::detail::cpu {

template <class T>
void node_relative(State<T>& s, const gpu::PassConstants& pc, Range r) {
    const uint64_t pose = uint64_t(pc.src_half) * s.total_chains;
    for (uint32_t i = r.begin; i < r.end; ++i) {
        Element e = element_of(i, pc.model_node_count);
        int32_t owner = s.node_owner[pc.model_node_begin + e.index];
        const auto& local = s.node_local[pc.model_node_begin + e.index];
        auto u = s.chain_rotation[pose + state_chain(pc, e.instance, owner)] *
                 typename State<T>::vec3(local);
        s.node_relative[state_node(pc, e.instance, int32_t(e.index))] = {u, T(0)};
    }
}

template void node_relative<float>(State<float>&, const gpu::PassConstants&, Range);
template void node_relative<double>(State<double>&, const gpu::PassConstants&, Range);

}  // namespace hmsm::detail::cpu
