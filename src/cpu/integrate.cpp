// Pass 2: symplectic Euler on the two joint angles of each chain, clamped at max_angle, then
// the local transform T = Q Rz(theta_z) Rx(theta_x) (trunk: Ry(yaw) in front).
#include "cpu_state.h"

#include <cmath>

namespace hmsm::detail::cpu {

template <class T>
void integrate(State<T>& s, const gpu::PassConstants& pc, Range r) {
    using mat3 = typename State<T>::mat3;
    using vec3 = typename State<T>::vec3;
    for (uint32_t i = r.begin; i < r.end; ++i) {
        Element e = element_of(i, pc.model_chain_count);
        uint64_t c = state_chain(pc, e.instance, int32_t(e.index));
        const auto& k = s.chain_constants[pc.model_chain_begin + e.index];  // (I, K, D, A)
        auto& sv = s.chain_state[c];
        const auto& g = s.chain_force[c];
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

        T cx = std::cos(angle[0]), sx = std::sin(angle[0]);
        T cz = std::cos(angle[1]), sz = std::sin(angle[1]);
        mat3 rx(vec3(1, 0, 0), vec3(0, cx, sx), vec3(0, -sx, cx));  // columns
        mat3 rz(vec3(cz, sz, 0), vec3(-sz, cz, 0), vec3(0, 0, 1));
        mat3 t = s.chain_rest_rotation[pc.model_chain_begin + e.index] * rz * rx;
        if (s.chain_parent[pc.model_chain_begin + e.index] < 0) {
            const auto& yaw = s.instance_yaw[pc.instance_begin + e.instance];  // (cos, sin)
            mat3 ry(vec3(yaw.x, 0, -yaw.y), vec3(0, 1, 0), vec3(yaw.y, 0, yaw.x));
            t = ry * t;
        }
        s.chain_local[c] = t;
    }
}

template void integrate<float>(State<float>&, const gpu::PassConstants&, Range);
template void integrate<double>(State<double>&, const gpu::PassConstants&, Range);

}  // namespace hmsm::detail::cpu
