// Pass 1: generalized wind force per chain, from the wind in the chain's previous-step frame:
// w = lambda_i s Y(tau + phi_i) d (atmospheric: a vector, instance_wind_vector) + the force
// fields at the chain's previous origin (docs/model.md 3.5, 3.7, 3.9; the wind table layout is
// in gpu_layout.h).
#include "cpu_state.h"

#include "../common/wind_profile.h"

#include <algorithm>
#include <cmath>

namespace hmsm::detail::cpu {

/// lambda_i s Y(tau + phi_i) d of group instance k at wind-table step slot `slot` (atmospheric:
/// lambda_i s (e_x (1 + u') + e_y v' + e_z w')): the part of the wind that depends only on the
/// instance and the step.
template <class T>
typename State<T>::vec3 instance_wind_vector(const State<T>& s, const gpu::PassConstants& pc, uint32_t slot, uint32_t k) {
    using vec3 = typename State<T>::vec3;
    const auto* table = s.wind_table.data();
    const auto* step_phase = &table[HMSM_WIND_STEPS + HMSM_WIND_STEP_VEC4S * slot];
    const auto& instance = s.instance_wind[pc.instance_begin + k];
    if (pc.profile == HMSM_WIND_PROFILE_ATMOSPHERIC) {
        const auto c = atmospheric_components<T>(&table[HMSM_WIND_AMPLITUDES].x, &step_phase[1].x, &instance[4]);
        return instance[0] * (c.along * vec3(table[HMSM_WIND_VECTOR]) + c.lateral * vec3(table[HMSM_WIND_LATERAL]) +
                              c.vertical * vec3(table[HMSM_WIND_VERTICAL]));
    }
    T y;
    if (pc.profile == HMSM_WIND_PROFILE_TURBULENT)
        y = turbulent_y<T>(&table[HMSM_WIND_AMPLITUDES].x, &step_phase[1].x, &instance[4]);
    else
        y = wind_profile_y<T>(pc.profile, step_phase[0].x + instance[1]);  // tau + phi, both mod 2
    return instance[0] * y * vec3(table[HMSM_WIND_VECTOR]);
}

/// g for every chain of the work items, handed to use(state chain, group instance, static chain,
/// g); the previous pose from the pose half src_half, or from the joint matrix (`from_joint`: a
/// path walk).
template <class T, class Use>
void wind_forces(State<T>& s, const gpu::PassConstants& pc, uint32_t wind_slot, Range r, bool from_joint, Use&& use) {
    using vec3 = typename State<T>::vec3;
    const auto* table = s.wind_table.data();
    const uint32_t fields = uint32_t(table[HMSM_WIND_VECTOR].w);
    // The coupled dynamics: the half of chain_load this step writes (the wind table's step slot)
    // and the other, which the last step wrote.
    const uint32_t load_written = uint32_t(table[HMSM_WIND_STEPS + HMSM_WIND_STEP_VEC4S * wind_slot].y);
    // The instance's wind is evaluated once per run of consecutive chains of one instance (a
    // range holds whole instances but for its ends), not per chain.
    uint32_t wind_instance = UINT32_MAX;
    vec3 wind_of_instance(0);
    for (uint32_t i = r.begin; i < r.end; ++i) {
        Element e = element_of(i, pc.model_chain_count);
        if (instance_paused(s, pc, e.instance)) continue;
        uint64_t c = state_chain(pc, e.instance, int32_t(e.index));
        if (e.instance != wind_instance) {
            wind_of_instance = instance_wind_vector(s, pc, wind_slot, e.instance);
            wind_instance = e.instance;
        }
        vec3 w = wind_of_instance;
        const uint64_t pose = pc.src_half * s.total_chains + c;
        const vec3 x = from_joint ? joint_origin(s, c) : vec3(s.chain_origin[pose]);
        for (uint32_t f = 0; f < fields; ++f) {
            const auto& sphere = table[HMSM_WIND_FIELDS + 2 * f];
            const auto& force = table[HMSM_WIND_FIELDS + 2 * f + 1];
            const vec3 offset = x - vec3(sphere);
            const T distance = std::sqrt(offset.x * offset.x + offset.y * offset.y + offset.z * offset.z);
            const T reach = std::max(T(0), T(1) - distance / sphere.w);
            if (!(reach > T(0))) continue;  // outside the sphere: no contribution at all (never 0 * F)
            const T h = reach * reach;
            if (force.w == T(0)) w += h * vec3(force);
            else if (distance >= T(1e-9)) w += (h * force.x / distance) * offset;
        }
        auto w_local = glm::transpose(from_joint ? joint_rotation(s, c) : s.chain_rotation[pose]) * w;
        if (pc.dynamics == HMSM_PASS_DYNAMICS_ARTICULATED) {  // pass 2 sweeps the impulses
            articulated_impulse(s, c, pc.model_chain_begin + e.index, w_local);
            continue;
        }
        if (pc.dynamics == HMSM_PASS_DYNAMICS_COUPLED) {
            const auto g = coupled_force(s, pc, e.instance, c, pc.model_chain_begin + e.index, w_local, 1 - load_written);
            s.chain_load[load_written * s.total_chains + c] = {g.x, g.y};  // the parent's next load
            use(c, e.instance, pc.model_chain_begin + e.index, g);
            continue;
        }
        T area = s.chain_constants[pc.model_chain_begin + e.index].w;
        use(c, e.instance, pc.model_chain_begin + e.index, typename State<T>::vec2(area * w_local.z, -area * w_local.x));
    }
}

template <class T>
void wind_force(State<T>& s, const gpu::PassConstants& pc, uint32_t wind_slot, Range r) {
    wind_forces(s, pc, wind_slot, r, false,
                [&](uint64_t c, uint32_t, uint32_t, const typename State<T>::vec2& g) { s.chain_force[c] = g; });
}

/// Composition::path_walk: integrate in the same pass over the same chains, g kept in hand;
/// only the new angles are stored (the walk computes T from them). The previous pose is the
/// joint matrix (a walk step writes no R or O half).
template <class T>
void wind_force_and_integrate(State<T>& s, const gpu::PassConstants& pc, uint32_t wind_slot, Range r) {
    wind_forces(s, pc, wind_slot, r, true,
                [&](uint64_t c, uint32_t instance, uint32_t model_chain, const typename State<T>::vec2& g) {
                    step_angles(s, pc, wind_slot, instance, model_chain, c, g);
                });
}

template void wind_force<float>(State<float>&, const gpu::PassConstants&, uint32_t, Range);
template void wind_force<double>(State<double>&, const gpu::PassConstants&, uint32_t, Range);
template void wind_force_and_integrate<float>(State<float>&, const gpu::PassConstants&, uint32_t, Range);
template void wind_force_and_integrate<double>(State<double>&, const gpu::PassConstants&, uint32_t, Range);

}  // namespace hmsm::detail::cpu
