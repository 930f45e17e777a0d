// The coupled dynamics on the CPU (docs/model.md 3.13): pass 1's generalized force from the
// wind moment, the children's loads and aerodynamic damping; pass 2's exact step of the damped
// oscillator with the force held; the math is src/common/coupled_math.h.
#include "cpu_state.h"

#include "../common/coupled_math.h"

namespace hmsm::detail::cpu {

template <class T>
typename State<T>::vec2 coupled_force(const State<T>& s, const gpu::PassConstants& pc, uint32_t instance,
                                      uint64_t c, uint32_t model_chain, const typename State<T>::vec3& w_local,
                                      uint32_t load_half) {
    const T* record = s.chain_dynamics[model_chain].data();
    T g[2];
    coupled_wind_torque(record, w_local.x, w_local.y, w_local.z, g);
    // Each child's load of the last step (its wind, its own children's loads and its
    // aerodynamic damping), passed on by its joint; from the half the last step wrote.
    int32_t first = 0, count = 0;
    coupled_children(record, first, count);
    for (int32_t j = first; j < first + count; ++j) {
        const auto& load = s.chain_load[load_half * s.total_chains + state_chain(pc, instance, j)];
        const T* child = s.chain_dynamics[pc.model_chain_begin + uint32_t(j)].data();
        coupled_add_child_load(child + 4 * HMSM_CHAIN_DYNAMICS_PASSING, load.x, load.y, g);
    }
    const auto& sv = s.chain_state[c];
    const T rate[2] = {sv.z, sv.w};
    coupled_subtract_aero_damping(record, glm::dot(w_local, w_local), rate, g);
    return {g[0], g[1]};
}

template <class T>
typename State<T>::vec2 coupled_integrate_angles(State<T>& s, uint32_t model_chain, uint64_t c,
                                                 const typename State<T>::vec2& g) {
    const T* record = s.chain_dynamics[model_chain].data();
    auto& sv = s.chain_state[c];
    T angle[2] = {sv.x, sv.y};
    T rate[2] = {sv.z, sv.w};
    for (uint32_t j = 0; j < 2; ++j) coupled_step_axis(record, j, g[int(j)], s.max_angle, angle[j], rate[j]);
    sv = {angle[0], angle[1], rate[0], rate[1]};
    return {angle[0], angle[1]};
}

template State<float>::vec2 coupled_force<float>(const State<float>&, const gpu::PassConstants&, uint32_t,
                                                  uint64_t, uint32_t, const State<float>::vec3&, uint32_t);
template State<double>::vec2 coupled_force<double>(const State<double>&, const gpu::PassConstants&, uint32_t,
                                                    uint64_t, uint32_t, const State<double>::vec3&, uint32_t);
template State<float>::vec2 coupled_integrate_angles<float>(State<float>&, uint32_t, uint64_t,
                                                             const State<float>::vec2&);
template State<double>::vec2 coupled_integrate_angles<double>(State<double>&, uint32_t, uint64_t,
                                                               const State<double>::vec2&);

}  // namespace hmsm::detail::cpu
