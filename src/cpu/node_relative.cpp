// Pass 4: each node's position relative to its chain's origin, u_n = R_owner l_n.
#include "cpu_state.h"

namespace hmsm::detail::cpu {

template <class T>
void node_relative(State<T>& s, const gpu::PassConstants& pc, Range r) {
    const uint64_t pose = uint64_t(pc.src_half) * s.total_chains;
    for (uint32_t i = r.begin; i < r.end; ++i) {
        Element e = element_of(i, pc.model_node_count);
        if (instance_paused(s, pc, e.instance)) continue;
        int32_t owner = s.node_owner[pc.model_node_begin + e.index];
        const auto& local = s.node_local[pc.model_node_begin + e.index];
        auto u = s.chain_rotation[pose + state_chain(pc, e.instance, owner)] *
                 typename State<T>::vec3(local);
        s.node_relative[state_node(pc, e.instance, int32_t(e.index))] = {u, T(0)};
    }
}

/// Composition::path_walk: node_world in the same pass, u kept in hand (not stored), the pose
/// from the joint matrix (a walk step writes no R or O half).
template <class T>
void node_relative_and_world(State<T>& s, const gpu::PassConstants& pc, Range r) {
    for (uint32_t i = r.begin; i < r.end; ++i) {
        Element e = element_of(i, pc.model_node_count);
        if (instance_paused(s, pc, e.instance)) continue;
        int32_t owner = s.node_owner[pc.model_node_begin + e.index];
        const uint64_t chain = state_chain(pc, e.instance, owner);
        const auto u = joint_rotation(s, chain) * typename State<T>::vec3(s.node_local[pc.model_node_begin + e.index]);
        const auto w = joint_origin(s, chain) + u;
        s.node_world[state_node(pc, e.instance, int32_t(e.index))] = {w.x, w.y, w.z, T(1)};
    }
}

template void node_relative<float>(State<float>&, const gpu::PassConstants&, Range);
template void node_relative<double>(State<double>&, const gpu::PassConstants&, Range);
template void node_relative_and_world<float>(State<float>&, const gpu::PassConstants&, Range);
template void node_relative_and_world<double>(State<double>&, const gpu::PassConstants&, Range);

}  // namespace hmsm::detail::cpu
