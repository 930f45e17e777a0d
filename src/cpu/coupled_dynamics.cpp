// The coupled dynamics on the CPU (docs/model.md 3.13): pass 1's generalized force from the
// wind moment, the children's loads and aerodynamic damping; pass 2's exact step of the damped
// oscillator with the force held. Mirrored by kernels/cuda/coupled_math.cuh and
// shaders/glsl/coupled_math.glsl.
#include "cpu_state.h"

#include <cmath>

namespace hmsm::detail::cpu {

namespace {

/// Scalar j of vec4 `v` of a chain's record.
template <class T>
T field(const std::array<T, 4 * HMSM_CHAIN_DYNAMICS_VEC4S>& record, uint32_t v, uint32_t j) {
    return record[4 * v + j];
}

}  // namespace

template <class T>
typename State<T>::vec2 coupled_force(const State<T>& s, const gpu::PassConstants& pc, uint32_t instance,
                                      uint64_t c, uint32_t model_chain, const typename State<T>::vec3& w_local,
                                      uint32_t load_half) {
    using vec2 = typename State<T>::vec2;
    using vec3 = typename State<T>::vec3;
    const auto& k = s.chain_dynamics[model_chain];
    // Wind: the torque (q_ref M) x w_local about the joint, its x and z components.
    const vec3 moment(field(k, 4, 0), field(k, 4, 1), field(k, 4, 2));
    const vec3 torque = glm::cross(moment, w_local);
    vec2 g(torque.x, torque.z);
    // Each child's load of the last step (its wind, its own children's loads and its
    // aerodynamic damping), which its joint passes on, rotated from the child's frame into this
    // one by its rest rotation Q; from the half of chain_load the last step wrote.
    const int32_t first = int32_t(field(k, 5, 0)), count = int32_t(field(k, 5, 1));
    for (int32_t j = first; j < first + count; ++j) {
        const auto& load = s.chain_load[load_half * s.total_chains + state_chain(pc, instance, j)];
        const vec3 passed = s.chain_rest_rotation[pc.model_chain_begin + uint32_t(j)] * vec3(load.x, T(0), load.y);
        g += vec2(passed.x, passed.z);
    }
    // Aerodynamic damping D_a = aero sqrt(|w|), held as the torque that takes from the rate what
    // exp(-D_a dt / I) would over one step: never more than the rate itself.
    const T speed = std::sqrt(std::sqrt(glm::dot(w_local, w_local)));
    const auto& sv = s.chain_state[c];
    const T rate[2] = {sv.z, sv.w};
    for (int a = 0; a < 2; ++a) {
        const T damping = field(k, 3, 2 + a) * speed;
        const T x = damping * s.dt / field(k, 2, a);
        const T share = x > T(1e-4) ? (T(1) - std::exp(-x)) / x : T(1) - T(0.5) * x;
        g[a] -= damping * share * rate[a];
    }
    return g;
}

template <class T>
typename State<T>::vec2 coupled_integrate_angles(State<T>& s, uint32_t model_chain, uint64_t c,
                                                 const typename State<T>::vec2& g) {
    const auto& k = s.chain_dynamics[model_chain];
    auto& sv = s.chain_state[c];
    T angle[2] = {sv.x, sv.y};
    T rate[2] = {sv.z, sv.w};
    for (int j = 0; j < 2; ++j) {
        // Exact over dt for the force held: the offset from the equilibrium g/K turns by the
        // transition of this axis.
        const T equilibrium = g[j] / field(k, 2, 2 + j);
        const T offset = angle[j] - equilibrium;
        const T next_rate = field(k, j, 2) * offset + field(k, j, 3) * rate[j];
        angle[j] = equilibrium + field(k, j, 0) * offset + field(k, j, 1) * rate[j];
        rate[j] = next_rate;
        if (std::abs(angle[j]) > s.max_angle) {
            angle[j] = std::copysign(s.max_angle, angle[j]);
            rate[j] = T(0);
        }
    }
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
