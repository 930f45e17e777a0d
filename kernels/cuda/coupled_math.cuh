// The coupled dynamics of passes 1 and 2 (docs/model.md 3.13) for the CUDA kernels: the
// generalized force from the wind moment, the children's loads and the aerodynamic damping, and
// the exact step of the damped oscillator with the force held. The math is
// src/common/coupled_math.h, shared with src/cpu/coupled_dynamics.cpp; these functions load a
// chain's data from the device buffers and hand it over.
#pragma once

#include "pass_math.cuh"

#include "../../src/common/coupled_math.h"

namespace hmsm::detail::cuda {

/// Vec4 j of static chain model_chain's record, stored by vec4 (gpu_layout.h).
HMSM_HOST_DEVICE const float4* coupled_vec4(const BufferPointers& b, const gpu::PassConstants& pc,
                                            uint32_t model_chain, uint32_t j) {
    return b.chain_dynamics + uint64_t(j) * pc.total_model_chains + model_chain;
}

/// A chain's record of kCount vec4 in chain_dynamics (the held exchange's,
/// HMSM_CHAIN_DYNAMICS_VEC4S, or the articulated exchange's, HMSM_CHAIN_ARTICULATED_VEC4S) as
/// scalars: the vec4s whose bits are set in kVec4s loaded whole through the read-only path (the
/// compiler keeps read-only loads whose values go unused), the others 0.
template <uint32_t kCount>
struct RecordScalars {
    float s[4 * kCount];
};
template <uint32_t kCount, uint32_t kVec4s>
HMSM_HOST_DEVICE RecordScalars<kCount> load_record(const BufferPointers& b, const gpu::PassConstants& pc,
                                                   uint32_t model_chain) {
    RecordScalars<kCount> record;
#pragma unroll
    for (uint32_t j = 0; j < kCount; ++j) {
        const float4 x =
            (kVec4s >> j & 1u) ? load(coupled_vec4(b, pc, model_chain, j)) : make_float4(0.0f, 0.0f, 0.0f, 0.0f);
        record.s[4 * j] = x.x;
        record.s[4 * j + 1] = x.y;
        record.s[4 * j + 2] = x.z;
        record.s[4 * j + 3] = x.w;
    }
    return record;
}
using CoupledRecord = RecordScalars<HMSM_CHAIN_DYNAMICS_VEC4S>;
template <uint32_t kVec4s>
HMSM_HOST_DEVICE CoupledRecord load_coupled_record(const BufferPointers& b, const gpu::PassConstants& pc,
                                                   uint32_t model_chain) {
    return load_record<HMSM_CHAIN_DYNAMICS_VEC4S, kVec4s>(b, pc, model_chain);
}

/// The half of chain_load the step of wind-table slot pc.wind_slot writes; it reads the other
/// (gpu_layout.h).
HMSM_HOST_DEVICE uint32_t load_half_written(const BufferPointers& b, const gpu::PassConstants& pc) {
    return uint32_t(load(b.wind_table + HMSM_WIND_STEPS + HMSM_WIND_STEP_VEC4S * pc.wind_slot).y);
}

/// Pass 1 of the coupled dynamics for model chain c of group instance k (state chain `chain`),
/// with the wind w_local in the chain's frame of the previous step; reads the children's loads
/// from half 1 - `written` and stores g as the chain's load in half `written`, for its parent's
/// next step. Per child two vec4 loads: its load and the passing vec4 of its record (the
/// children are consecutive chains, so a thread's loads run along two arrays of vec4).
HMSM_HOST_DEVICE float2 coupled_force(const BufferPointers& b, const gpu::PassConstants& pc, uint32_t k,
                                      uint64_t chain, uint32_t c, float3 w_local, uint32_t written) {
    // (I/dt, 1/K), (aero dt/I, children), wind moment.
    const CoupledRecord record = load_coupled_record<0b11100u>(b, pc, pc.model_chain_begin + c);
    float g[2];
    coupled_wind_torque(record.s, w_local.x, w_local.y, w_local.z, g);
    // Each child's load of the last step, passed on by its joint.
    int32_t first = 0, count = 0;
    coupled_children(record.s, first, count);
    const float2* loads = b.chain_load + half_begin(pc, 1u - written);
    const float4* passings = coupled_vec4(b, pc, pc.model_chain_begin, HMSM_CHAIN_DYNAMICS_PASSING);
    for (int32_t j = first; j < first + count; ++j) {
        const float2 load_j = load(loads + state_chain(pc, k, j));
        const float4 p = load(passings + j);
        const float passing[4] = {p.x, p.y, p.z, p.w};
        coupled_add_child_load(passing, load_j.x, load_j.y, g);
    }
    const float4 state = load(b.chain_state + chain);
    const float rate[2] = {state.z, state.w};
    coupled_subtract_aero_damping(record.s, dot(w_local, w_local), rate, g);
    b.chain_load[half_begin(pc, written) + chain] = make_float2(g[0], g[1]);
    return make_float2(g[0], g[1]);
}

/// Pass 2 of the coupled dynamics: the exact step of static chain model_chain from `state`
/// under g held, clamped at max_angle; returns the new state.
HMSM_HOST_DEVICE float4 coupled_step(const BufferPointers& b, const gpu::PassConstants& pc, uint32_t model_chain,
                                     float4 state, float2 g_force) {
    const CoupledRecord record = load_coupled_record<0b00111u>(b, pc, model_chain);  // transitions, 1/K
    const float max_angle = pc.params.y;
    coupled_step_axis(record.s, 0u, g_force.x, max_angle, state.x, state.z);
    coupled_step_axis(record.s, 1u, g_force.y, max_angle, state.y, state.w);
    return state;
}

}  // namespace hmsm::detail::cuda
