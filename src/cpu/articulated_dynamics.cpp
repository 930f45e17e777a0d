// The coupled dynamics' articulated exchange on the CPU (docs/model.md 3.13): pass 1's impulse
// of each chain's own wind and aerodynamic damping; pass 2's sweeps over each instance's chains,
// up from the last chain (its children's forces gathered, its joint's free impulse solved) and
// down from the trunk (each joint's change of rate given its parent's), then each joint's step.
// The math is src/common/articulated_math.h.
#include "cpu_state.h"

#include "../common/articulated_math.h"

#include <array>
#include <vector>

namespace hmsm::detail::cpu {

template <class T>
void articulated_impulse(State<T>& s, uint64_t c, uint32_t model_chain, const typename State<T>::vec3& w_local) {
    const auto& sv = s.chain_state[c];
    const T rate[2] = {sv.z, sv.w};
    T impulse[8];
    articulated_wind_impulse(s.chain_articulated[model_chain].data(), w_local.x, w_local.y, w_local.z, rate, impulse);
    for (int i = 0; i < 8; ++i) s.chain_local[c][i / 3][i % 3] = impulse[i];  // where T goes (cpu_state.h)
}

template <class T>
void articulated_integrate(State<T>& s, const gpu::PassConstants& pc, uint32_t wind_slot, Range r) {
    const uint32_t n = pc.model_chain_count;
    // Per chain of the instance being swept: the force it passes to its parent, its w, its
    // spatial change of motion.
    thread_local std::vector<std::array<T, 6>> passed, motion;
    thread_local std::vector<std::array<T, 2>> free_rate;
    passed.resize(n);
    motion.resize(n);
    free_rate.resize(n);
    const T dt = s.dt;
    for (uint32_t k = r.begin; k < r.end; ++k) {
        if (instance_paused(s, pc, k)) continue;
        for (uint32_t j = n; j-- > 0;) {
            const uint32_t model_chain = pc.model_chain_begin + j;
            const T* record = s.chain_articulated[model_chain].data();
            T p[6] = {};
            const uint32_t first = uint32_t(articulated_field(record, 42));
            const uint32_t count = uint32_t(articulated_field(record, 43));
            for (uint32_t child = first; child < first + count; ++child)
                for (int i = 0; i < 6; ++i) p[i] += passed[child][size_t(i)];
            const uint64_t c = state_chain(pc, k, int32_t(j));
            const auto& sv = s.chain_state[c];
            const T angle[2] = {sv.x, sv.y}, rate[2] = {sv.z, sv.w};
            T impulse[8];
            for (int i = 0; i < 8; ++i) impulse[i] = s.chain_local[c][i / 3][i % 3];
            articulated_up(record, angle, rate, impulse, p, free_rate[j].data(), passed[j].data());
        }
        for (uint32_t j = 0; j < n; ++j) {
            const uint32_t model_chain = pc.model_chain_begin + j;
            const T* record = s.chain_articulated[model_chain].data();
            const int32_t parent = s.chain_parent[model_chain];
            T dv[2];
            articulated_down(record, parent >= 0 ? motion[size_t(parent)].data() : nullptr, free_rate[j].data(), dv,
                             motion[j].data());
            const uint64_t c = state_chain(pc, k, int32_t(j));
            auto& sv = s.chain_state[c];
            T angle[2] = {sv.x, sv.y}, rate[2] = {sv.z, sv.w};
            articulated_step(record, dt, s.max_angle, dv, angle, rate);
            sv = {angle[0], angle[1], rate[0], rate[1]};
            const auto relaxed = relax_fading(s, pc, wind_slot, k, model_chain, c);
            s.chain_local[c] = local_transform(s, model_chain, pc.instance_begin + k, relaxed);
        }
    }
}

template void articulated_impulse<float>(State<float>&, uint64_t, uint32_t, const State<float>::vec3&);
template void articulated_impulse<double>(State<double>&, uint64_t, uint32_t, const State<double>::vec3&);
template void articulated_integrate<float>(State<float>&, const gpu::PassConstants&, uint32_t, Range);
template void articulated_integrate<double>(State<double>&, const gpu::PassConstants&, uint32_t, Range);

}  // namespace hmsm::detail::cpu
