// Pass 2: symplectic Euler on the two joint angles S = (theta_x, theta_z) of each chain,
// F = g - K S - D V, V += dt/I F, S += dt V, clamped at max_angle (the rate is zeroed at the
// stop); then the local transform T = Q Rz(theta_z) Rx(theta_x), with Ry(yaw) in front for the
// trunk.
#include "pass_math.cuh"

#include <cmath>

namespace hmsm::detail::cuda {

static HMSM_HOST_DEVICE void integrate_element(const BufferPointers& b,
                                               const gpu::PassConstants& pc, uint32_t i) {
    const Element e = element_of(i, pc.model_chain_count);
    const uint64_t chain = pc.chain_begin + i;
    const uint32_t model_chain = pc.model_chain_begin + e.index;
    const float4 k = load(b.chain_constants + model_chain);  // (I, K, D, A)
    const float4 state = b.chain_state[chain];               // (theta_x, theta_z, v_x, v_z)
    const float2 force = b.chain_force[chain];
    const float dt = pc.params.x, max_angle = pc.params.y;

    float angle[2] = {state.x, state.y};
    float rate[2] = {state.z, state.w};
    const float g[2] = {force.x, force.y};
#pragma unroll
    for (int j = 0; j < 2; ++j) {
        const float f = g[j] - k.y * angle[j] - k.z * rate[j];
        rate[j] += dt / k.x * f;
        angle[j] += dt * rate[j];
        if (fabsf(angle[j]) > max_angle) {
            angle[j] = copysignf(max_angle, angle[j]);
            rate[j] = 0.0f;
        }
    }
    b.chain_state[chain] = make_float4(angle[0], angle[1], rate[0], rate[1]);

    float sx, cx, sz, cz;
    sincosf(angle[0], &sx, &cx);
    sincosf(angle[1], &sz, &cz);
    // Rz(theta_z) Rx(theta_x), by columns.
    const Mat3 bend = {make_float3(cz, sz, 0.0f), make_float3(-sz * cx, cz * cx, sx),
                       make_float3(sz * sx, -cz * sx, cx)};
    Mat3 local = load_mat3(b.chain_rest_rotation, model_chain) * bend;
    if (load(b.chain_parent + model_chain) < 0) {
        const float4 yaw = load(b.instance_yaw + pc.instance_begin + e.instance);  // (cos, sin)
        const Mat3 ry = {make_float3(yaw.x, 0.0f, -yaw.y), make_float3(0.0f, 1.0f, 0.0f),
                         make_float3(yaw.y, 0.0f, yaw.x)};
        local = ry * local;
    }
    store_mat3(b.chain_local, chain, local);
}

HMSM_CUDA_PASS(integrate)

}  // namespace hmsm::detail::cuda
