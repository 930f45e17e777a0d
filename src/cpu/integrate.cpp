// Pass 2: symplectic Euler on the two joint angles of each chain, clamped at max_angle (or the
// coupled dynamics' exact step), a fade's factor where one relaxes the chain, then the local
// transform T = Q Rz(theta_z) Rx(theta_x) (trunk: Ry(yaw) in front). The two halves
// are apart for the path walk, which stores the angles and computes T where it multiplies it.
#include "cpu_state.h"

#include "../common/fade_math.h"

#include <cmath>

namespace hmsm::detail::cpu {

template <class T>
typename State<T>::vec2 integrate_angles(State<T>& s, uint32_t model_chain, uint64_t c,
                                         const typename State<T>::vec2& g) {
    const auto& k = s.chain_constants[model_chain];  // (I, K, D, A)
    auto& sv = s.chain_state[c];
    T angle[2] = {sv.x, sv.y};
    T rate[2] = {sv.z, sv.w};
    for (int j = 0; j < 2; ++j) {
        T force = g[j] - k.y * angle[j] - k.z * rate[j];
        rate[j] += s.dt / k.x * force;
        angle[j] += s.dt * rate[j];
        if (std::abs(angle[j]) > s.max_angle) {
            angle[j] = std::copysign(s.max_angle, angle[j]);
            rate[j] = T(0);
        }
    }
    sv = {angle[0], angle[1], rate[0], rate[1]};
    return {angle[0], angle[1]};
}

template <class T>
typename State<T>::mat3 local_transform(const State<T>& s, uint32_t model_chain, uint32_t instance,
                                        const typename State<T>::vec2& angle) {
    using mat3 = typename State<T>::mat3;
    using vec3 = typename State<T>::vec3;
    T cx = std::cos(angle[0]), sx = std::sin(angle[0]);
    T cz = std::cos(angle[1]), sz = std::sin(angle[1]);
    mat3 rx(vec3(1, 0, 0), vec3(0, cx, sx), vec3(0, -sx, cx));  // columns
    mat3 rz(vec3(cz, sz, 0), vec3(-sz, cz, 0), vec3(0, 0, 1));
    mat3 t = s.chain_rest_rotation[model_chain] * rz * rx;
    if (s.chain_parent[model_chain] < 0) {
        const auto& yaw = s.instance_yaw[instance];  // (cos, sin)
        mat3 ry(vec3(yaw.x, 0, -yaw.y), vec3(0, 1, 0), vec3(yaw.y, 0, yaw.x));
        t = ry * t;
    }
    return t;
}

template <class T>
typename State<T>::vec2 step_angles(State<T>& s, const gpu::PassConstants& pc, uint32_t wind_slot, uint32_t instance,
                                    uint32_t model_chain, uint64_t c, const typename State<T>::vec2& g) {
    // Both store S and V in chain_state, which the fade then reads.
    if (pc.dynamics == HMSM_PASS_DYNAMICS_COUPLED) coupled_integrate_angles(s, model_chain, c, g);
    else integrate_angles(s, model_chain, c, g);
    return relax_fading(s, pc, wind_slot, instance, model_chain, c);
}

template <class T>
typename State<T>::vec2 relax_fading(State<T>& s, const gpu::PassConstants& pc, uint32_t wind_slot, uint32_t instance,
                                     uint32_t model_chain, uint64_t c) {
    // The fade (docs/model.md 3.12, fading to a coarser level): S and V of a chain the level the
    // instance fades to folds, times the step's factor (src/common/fade_math.h).
    const uint32_t word = uint32_t(s.instance_wind[pc.instance_begin + instance][3]);
    if (word == 0u || !fade_relaxes(word, s.chain_keep_level[model_chain]))
        return {s.chain_state[c].x, s.chain_state[c].y};
    const uint32_t clock = uint32_t(s.wind_table[HMSM_WIND_STEPS + HMSM_WIND_STEP_VEC4S * wind_slot].z);
    const T sigma = fade_factor<T>(word, clock);
    auto& sv = s.chain_state[c];
    sv = sigma == T(0) ? typename State<T>::vec4(T(0)) : sigma * sv;
    return {sv.x, sv.y};
}

template <class T>
void integrate(State<T>& s, const gpu::PassConstants& pc, uint32_t wind_slot, Range r) {
    if (pc.kind == HMSM_DISPATCH_INSTANCE_SWEEP) return articulated_integrate(s, pc, wind_slot, r);
    for (uint32_t i = r.begin; i < r.end; ++i) {
        Element e = element_of(i, pc.model_chain_count);
        if (instance_paused(s, pc, e.instance)) continue;
        uint64_t c = state_chain(pc, e.instance, int32_t(e.index));
        const uint32_t model_chain = pc.model_chain_begin + e.index;
        const auto angle = step_angles(s, pc, wind_slot, e.instance, model_chain, c, s.chain_force[c]);
        s.chain_local[c] = local_transform(s, model_chain, pc.instance_begin + e.instance, angle);
    }
}

template void integrate<float>(State<float>&, const gpu::PassConstants&, uint32_t, Range);
template void integrate<double>(State<double>&, const gpu::PassConstants&, uint32_t, Range);
template State<float>::vec2 step_angles<float>(State<float>&, const gpu::PassConstants&, uint32_t, uint32_t, uint32_t,
                                               uint64_t, const State<float>::vec2&);
template State<double>::vec2 step_angles<double>(State<double>&, const gpu::PassConstants&, uint32_t, uint32_t,
                                                 uint32_t, uint64_t, const State<double>::vec2&);
template State<float>::vec2 relax_fading<float>(State<float>&, const gpu::PassConstants&, uint32_t, uint32_t,
                                                uint32_t, uint64_t);
template State<double>::vec2 relax_fading<double>(State<double>&, const gpu::PassConstants&, uint32_t, uint32_t,
                                                  uint32_t, uint64_t);
template State<float>::vec2 integrate_angles<float>(State<float>&, uint32_t, uint64_t, const State<float>::vec2&);
template State<double>::vec2 integrate_angles<double>(State<double>&, uint32_t, uint64_t, const State<double>::vec2&);
template State<float>::mat3 local_transform<float>(const State<float>&, uint32_t, uint32_t, const State<float>::vec2&);
template State<double>::mat3 local_transform<double>(const State<double>&, uint32_t, uint32_t,
                                                    const State<double>::vec2&);

}  // namespace hmsm::detail::cpu
