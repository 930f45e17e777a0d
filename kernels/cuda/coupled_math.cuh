// The coupled dynamics of passes 1 and 2 (docs/model.md 3.13) for the CUDA kernels: the
// generalized force from the wind moment, the children's loads and the aerodynamic damping, and
// the exact step of the damped oscillator with the force held. Mirrors
// src/cpu/coupled_dynamics.cpp and shaders/glsl/coupled_math.glsl line by line.
#pragma once

#include "pass_math.cuh"

namespace hmsm::detail::cuda {

/// vec4 `v` of model chain `model_chain`'s record (gpu_layout.h HMSM_CHAIN_DYNAMICS_VEC4S).
HMSM_HOST_DEVICE float4 coupled_record(const BufferPointers& b, uint32_t model_chain, uint32_t v) {
    return load(b.chain_dynamics + uint64_t(HMSM_CHAIN_DYNAMICS_VEC4S) * model_chain + v);
}

/// The half of chain_load the step of wind-table slot pc.wind_slot writes; it reads the other
/// (gpu_layout.h).
HMSM_HOST_DEVICE uint32_t load_half_written(const BufferPointers& b, const gpu::PassConstants& pc) {
    return uint32_t(load(b.wind_table + HMSM_WIND_STEPS + HMSM_WIND_STEP_VEC4S * pc.wind_slot).y);
}

/// Pass 1 of the coupled dynamics for model chain c of group instance k (state chain `chain`),
/// with the wind w_local in the chain's frame of the previous step; reads the children's loads
/// from half 1 - `written` and stores g as the chain's load in half `written`, for its parent's
/// next step.
HMSM_HOST_DEVICE float2 coupled_force(const BufferPointers& b, const gpu::PassConstants& pc, uint32_t k,
                                      uint64_t chain, uint32_t c, float3 w_local, uint32_t written) {
    const uint32_t model_chain = pc.model_chain_begin + c;
    // Wind: the torque (q_ref M) x w_local about the joint, its x and z components.
    const float4 moment = coupled_record(b, model_chain, 4);
    float2 g = make_float2(moment.y * w_local.z - moment.z * w_local.y, moment.x * w_local.y - moment.y * w_local.x);
    // Each child's load of the last step, rotated from the child's frame into this one by Q.
    const float4 children = coupled_record(b, model_chain, 5);
    const int32_t first = int32_t(children.x), count = int32_t(children.y);
    for (int32_t j = first; j < first + count; ++j) {
        const float4 load_j = load(b.chain_load + half_begin(pc, 1u - written) + state_chain(pc, k, j));
        const float3 passed = load_mat3(b.chain_rest_rotation, pc.model_chain_begin + uint32_t(j)) *
                              make_float3(load_j.x, 0.0f, load_j.y);
        g.x += passed.x;
        g.y += passed.z;
    }
    // Aerodynamic damping D_a = aero sqrt(|w|), held as the torque that takes from the rate what
    // exp(-D_a dt / I) would over one step.
    const float speed = sqrtf(sqrtf(dot(w_local, w_local)));
    const float4 state = load(b.chain_state + chain);
    const float4 inertia_stiffness = coupled_record(b, model_chain, 2);
    const float4 damping_record = coupled_record(b, model_chain, 3);
    const float dt = pc.params.x;
    const float rate[2] = {state.z, state.w};
    const float inertia[2] = {inertia_stiffness.x, inertia_stiffness.y};
    const float aero[2] = {damping_record.z, damping_record.w};
    float force[2] = {g.x, g.y};
#pragma unroll
    for (int a = 0; a < 2; ++a) {
        const float damping = aero[a] * speed;
        const float x = damping * dt / inertia[a];
        const float share = x > 1e-4f ? (1.0f - expf(-x)) / x : 1.0f - 0.5f * x;
        force[a] -= damping * share * rate[a];
    }
    b.chain_load[half_begin(pc, written) + chain] = make_float4(force[0], force[1], 0.0f, 0.0f);
    return make_float2(force[0], force[1]);
}

/// Pass 2 of the coupled dynamics: the exact step of static chain model_chain from `state`
/// under g held, clamped at max_angle; returns the new state.
HMSM_HOST_DEVICE float4 coupled_step(const BufferPointers& b, const gpu::PassConstants& pc, uint32_t model_chain,
                                     float4 state, float2 g_force) {
    const float4 transition[2] = {coupled_record(b, model_chain, 0), coupled_record(b, model_chain, 1)};
    const float4 inertia_stiffness = coupled_record(b, model_chain, 2);
    const float stiffness[2] = {inertia_stiffness.z, inertia_stiffness.w};
    const float max_angle = pc.params.y;
    float angle[2] = {state.x, state.y};
    float rate[2] = {state.z, state.w};
    const float g[2] = {g_force.x, g_force.y};
#pragma unroll
    for (int j = 0; j < 2; ++j) {
        // The offset from the equilibrium g/K turns by the transition of this axis.
        const float equilibrium = g[j] / stiffness[j];
        const float offset = angle[j] - equilibrium;
        const float next_rate = transition[j].z * offset + transition[j].w * rate[j];
        angle[j] = equilibrium + transition[j].x * offset + transition[j].y * rate[j];
        rate[j] = next_rate;
        if (fabsf(angle[j]) > max_angle) {
            angle[j] = copysignf(max_angle, angle[j]);
            rate[j] = 0.0f;
        }
    }
    return make_float4(angle[0], angle[1], rate[0], rate[1]);
}

}  // namespace hmsm::detail::cuda
