// Pass 1: generalized wind force per chain, from the wind in the chain's previous-step frame.
#include "cpu_state.h"

#include "../wind_profile.h"

namespace hmsm::detail::cpu {

template <class T>
void wind_force(State<T>& s, const gpu::PassConstants& pc, double wind_x, Range r) {
    for (uint32_t i = r.begin; i < r.end; ++i) {
        Element e = element_of(i, pc.model_chain_count);
        uint64_t c = state_chain(pc, e.instance, int32_t(e.index));
        const auto& origin = s.instance_origin[pc.instance_begin + e.instance];
        T x = T(wind_x) + origin.w;  // f*t + phi, both reduced mod 2
        auto w = s.wind_vector * wind_profile_y<T>(s.profile, x);
        auto w_local = glm::transpose(s.chain_rotation[pc.src_half * s.total_chains + c]) * w;
        T area = s.chain_constants[pc.model_chain_begin + e.index].w;
        s.chain_force[c] = typename State<T>::vec2(area * w_local.z, -area * w_local.x);
    }
}

template void wind_force<float>(State<float>&, const gpu::PassConstants&, double, Range);
template void wind_force<double>(State<double>&, const gpu::PassConstants&, double, Range);

}  // namespace hmsm::detail::cpu
