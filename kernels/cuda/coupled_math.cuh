// The coupled dynamics of passes 1 and 2 (docs/model.md 3.13) for the CUDA kernels: the
// generalized force from the wind moment, the children's loads and the aerodynamic damping, and
// the exact step of the damped oscillator with the force held. The math is
// src/common/coupled_math.h, shared with src/cpu/coupled_dynamics.cpp; these functions load a
// chain's data from the device buffers and hand it over.
#pragma once

#include "pass_math.cuh"

#include "../../src/common/coupled_math.h"

namespace hmsm::detail::cuda {

/// Model chain model_chain's record as scalars (gpu_layout.h HMSM_CHAIN_DYNAMICS_VEC4S).
HMSM_HOST_DEVICE const float* coupled_record(const BufferPointers& b, uint32_t model_chain) {
    return &b.chain_dynamics[uint64_t(HMSM_CHAIN_DYNAMICS_VEC4S) * model_chain].x;
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
    const float* record = coupled_record(b, pc.model_chain_begin + c);
    float g[2];
    coupled_wind_torque(record, w_local.x, w_local.y, w_local.z, g);
    // Each child's load of the last step, passed on by its joint (Q's columns 0 and 2).
    int32_t first = 0, count = 0;
    coupled_children(record, first, count);
    for (int32_t j = first; j < first + count; ++j) {
        const float4 load_j = load(b.chain_load + half_begin(pc, 1u - written) + state_chain(pc, k, j));
        const float4* q = b.chain_rest_rotation + 3 * uint64_t(pc.model_chain_begin + uint32_t(j));
        coupled_add_child_load(&q[0].x, &q[2].x, load_j.x, load_j.y, g);
    }
    const float4 state = load(b.chain_state + chain);
    const float rate[2] = {state.z, state.w};
    coupled_subtract_aero_damping(record, dot(w_local, w_local), rate, pc.params.x, g);
    b.chain_load[half_begin(pc, written) + chain] = make_float4(g[0], g[1], 0.0f, 0.0f);
    return make_float2(g[0], g[1]);
}

/// Pass 2 of the coupled dynamics: the exact step of static chain model_chain from `state`
/// under g held, clamped at max_angle; returns the new state.
HMSM_HOST_DEVICE float4 coupled_step(const BufferPointers& b, const gpu::PassConstants& pc, uint32_t model_chain,
                                     float4 state, float2 g_force) {
    const float* record = coupled_record(b, model_chain);
    const float max_angle = pc.params.y;
    coupled_step_axis(record, 0u, g_force.x, max_angle, state.x, state.z);
    coupled_step_axis(record, 1u, g_force.y, max_angle, state.y, state.w);
    return state;
}

}  // namespace hmsm::detail::cuda
