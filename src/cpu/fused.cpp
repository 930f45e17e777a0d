// Composition::fused on the CPU: passes 1-5 for one group instance after the other, each pass
// the very function of its own file over that instance alone (the rounds in one go, as
// HMSM_MODE_POINTER_JUMPING_IN_DISPATCH). On a GPU the fused dispatch saves launches; here it
// only reorders independent work (an instance's passes read only its own chains and nodes and
// the pose half of the previous step), so the results are bitwise those of the separate
// passes with the rounds in one dispatch, and cpu-parallel may split the instances over threads.
#include "cpu_state.h"

namespace hmsm::detail::cpu {

template <class T>
void fused(State<T>& s, const gpu::PassConstants& pc, double wind_x, Range r) {
    const uint32_t chains = pc.model_chain_count, nodes = pc.model_node_count;
    for (uint32_t k = r.begin; k < r.end; ++k) {
        // The dispatch's constants narrowed to group instance k.
        gpu::PassConstants one = pc;
        one.instance_begin = pc.instance_begin + k;
        one.chain_begin = pc.chain_begin + k * chains;
        one.node_begin = pc.node_begin + k * nodes;
        one.vertex_begin = pc.vertex_begin + k * pc.model_vertex_count;
        one.element_count = chains;
        one.mode = HMSM_MODE_POINTER_JUMPING;
        wind_force(s, one, wind_x, {0, chains});
        integrate(s, one, {0, chains});
        one.mode = HMSM_MODE_POINTER_JUMPING_IN_DISPATCH;  // pc.round: every round
        compose(s, one, {0, 1});
        one.mode = HMSM_MODE_POINTER_JUMPING;
        one.element_count = nodes;
        node_relative(s, one, {0, nodes});
        one.mode = HMSM_MODE_POINTER_JUMPING_IN_DISPATCH;
        one.element_count = chains;
        root_positions(s, one, {0, 1});
    }
}

template void fused<float>(State<float>&, const gpu::PassConstants&, double, Range);
template void fused<double>(State<double>&, const gpu::PassConstants&, double, Range);

}  // namespace hmsm::detail::cpu
