// The coupled dynamics' articulated exchange (docs/model.md 3.13) for the CUDA kernels: pass 1's
// impulse of a chain's own wind and aerodynamic damping, and pass 2's sweeps over an instance
// (INSTANCE_SWEEP: one block per instance, depth by depth with a barrier between depths). The
// math is src/common/articulated_math.h, shared with src/cpu/articulated_dynamics.cpp; these
// functions load a chain's record (in chain_dynamics' place) and its scratch (gpu_layout.h) and
// hand them over.
#pragma once

#include "chain_math.cuh"

#include "../../src/common/articulated_math.h"

namespace hmsm::detail::cuda {

/// A chain's record (gpu_layout.h HMSM_CHAIN_ARTICULATED_VEC4S, in the held records' place) as
/// scalars: the vec4s whose bits are set in kVec4s, the others 0 (coupled_math.cuh load_record).
using ArticulatedRecord = RecordScalars<HMSM_CHAIN_ARTICULATED_VEC4S>;
template <uint32_t kVec4s>
HMSM_HOST_DEVICE ArticulatedRecord load_articulated_record(const BufferPointers& b, const gpu::PassConstants& pc,
                                                           uint32_t model_chain) {
    return load_record<HMSM_CHAIN_ARTICULATED_VEC4S, kVec4s>(b, pc, model_chain);
}
/// Vec4 11 of model chain c's record: (first chain of its depth, end of its depth, 0, 0).
HMSM_HOST_DEVICE float4 articulated_depth(const BufferPointers& b, const gpu::PassConstants& pc, uint32_t c) {
    return load(b.chain_dynamics + uint64_t(11) * pc.total_model_chains + pc.model_chain_begin + c);
}

/// A chain's scratch of the step where integrate writes T (chain_local's columns 0 and 1:
/// gpu_layout.h) as 8 scalars, and back: its impulse, then what the up sweep passes on. Within
/// a sweep other threads of the block wrote them: plain loads, not the read-only path.
HMSM_HOST_DEVICE void load_kept(const BufferPointers& b, uint64_t chain, float v[8]) {
    const float4 low = b.chain_local[3 * chain], high = b.chain_local[3 * chain + 1];
    v[0] = low.x, v[1] = low.y, v[2] = low.z, v[3] = low.w;
    v[4] = high.x, v[5] = high.y, v[6] = high.z, v[7] = high.w;
}
HMSM_HOST_DEVICE void store_kept(const BufferPointers& b, uint64_t chain, const float v[8]) {
    b.chain_local[3 * chain] = make_float4(v[0], v[1], v[2], v[3]);
    b.chain_local[3 * chain + 1] = make_float4(v[4], v[5], v[6], v[7]);
}
/// A chain's spatial change of motion on the way down: its halves of chain_load, then
/// chain_force (gpu_layout.h).
HMSM_HOST_DEVICE void load_motion(const BufferPointers& b, const gpu::PassConstants& pc, uint64_t chain, float a[6]) {
    const float2 first = b.chain_load[chain], second = b.chain_load[half_begin(pc, 1) + chain];
    const float2 third = b.chain_force[chain];
    a[0] = first.x, a[1] = first.y, a[2] = second.x, a[3] = second.y, a[4] = third.x, a[5] = third.y;
}
HMSM_HOST_DEVICE void store_motion(const BufferPointers& b, const gpu::PassConstants& pc, uint64_t chain,
                                   const float a[6]) {
    b.chain_load[chain] = make_float2(a[0], a[1]);
    b.chain_load[half_begin(pc, 1) + chain] = make_float2(a[2], a[3]);
    b.chain_force[chain] = make_float2(a[4], a[5]);
}

/// Pass 1 for model chain c of group instance k (state chain `chain`) with the wind w_local in
/// the chain's frame of the previous step: its impulse over the step, where T goes.
HMSM_HOST_DEVICE void articulated_impulse(const BufferPointers& b, const gpu::PassConstants& pc, uint32_t c,
                                          uint64_t chain, float3 w_local) {
    // (G, eta), (dt q M, dt q A), (theta dt, I), (aero dt / I, children).
    const ArticulatedRecord record = load_articulated_record<0b11010001000u>(b, pc, pc.model_chain_begin + c);
    const float4 state = b.chain_state[chain];
    const float rate[2] = {state.z, state.w};
    float impulse[8];
    articulated_wind_impulse(record.s, w_local.x, w_local.y, w_local.z, rate, impulse);
    store_kept(b, chain, impulse);
}

/// The barrier between two depths of a sweep (none on the host, which runs one lane).
HMSM_HOST_DEVICE void sweep_barrier() {
#ifdef __CUDA_ARCH__
    __syncthreads();
#endif
}

/// Pass 2 for group instance k: lane `lane` of `lanes` (a block's threads; 0 of 1 on the host)
/// takes every lanes-th chain of each depth. Up from the deepest depth: each chain gathers the
/// forces its children pass on, solves its joint's free impulse and passes its own force on
/// (kept with its w where T goes); down from the trunk: each joint's change of rate given its
/// parent's change of motion (kept in chain_load and chain_force), its step, the fade and T.
HMSM_HOST_DEVICE void articulated_sweep(const BufferPointers& b, const gpu::PassConstants& pc, uint32_t k,
                                        uint32_t lane, uint32_t lanes) {
    const uint32_t n = pc.model_chain_count;
    for (uint32_t end = n; end > 0;) {
        const uint32_t begin = uint32_t(articulated_depth(b, pc, end - 1).x);
        for (uint32_t j = begin + lane; j < end; j += lanes) {  // U, G, Q and d, K and D, children
            const ArticulatedRecord record = load_articulated_record<0b10101111111u>(b, pc, pc.model_chain_begin + j);
            float p[6] = {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
            const uint32_t first = uint32_t(record.s[42]), last = first + uint32_t(record.s[43]);
            uint32_t child = first;
            for (; child + 4 <= last; child += 4) {  // four children's loads in flight together
                float passed[4][8];
#pragma unroll
                for (int c = 0; c < 4; ++c) load_kept(b, state_chain(pc, k, int32_t(child) + c), passed[c]);
#pragma unroll
                for (int c = 0; c < 4; ++c)
                    for (int i = 0; i < 6; ++i) p[i] += passed[c][i];
            }
            for (; child < last; ++child) {
                float passed[8];
                load_kept(b, state_chain(pc, k, int32_t(child)), passed);
                for (int i = 0; i < 6; ++i) p[i] += passed[i];
            }
            const uint64_t chain = state_chain(pc, k, int32_t(j));
            const float4 state = b.chain_state[chain];
            const float angle[2] = {state.x, state.y}, rate[2] = {state.z, state.w};
            float impulse[8], kept[8];
            load_kept(b, chain, impulse);
            articulated_up(record.s, angle, rate, impulse, p, kept + 6, kept);
            store_kept(b, chain, kept);
        }
        sweep_barrier();
        end = begin;
    }
    const float dt = pc.params.x, max_angle = pc.params.y;
    for (uint32_t begin = 0; begin < n;) {
        const uint32_t end = uint32_t(articulated_depth(b, pc, begin).y);
        for (uint32_t j = begin + lane; j < end; j += lanes) {  // U, G, Q and d, theta dt
            const uint32_t model_chain = pc.model_chain_begin + j;
            const ArticulatedRecord record = load_articulated_record<0b1001111111u>(b, pc, model_chain);
            const int32_t parent = load(b.chain_parent + model_chain);
            float from_parent[6], motion[6], dv[2];
            if (parent >= 0) load_motion(b, pc, state_chain(pc, k, parent), from_parent);
            const uint64_t chain = state_chain(pc, k, int32_t(j));
            const float4 kept = b.chain_local[3 * chain + 1];  // its w in z and w
            const float w[2] = {kept.z, kept.w};
            articulated_down(record.s, parent >= 0 ? from_parent : nullptr, w, dv, motion);
            const float4 state = b.chain_state[chain];
            float angle[2] = {state.x, state.y}, rate[2] = {state.z, state.w};
            articulated_step(record.s, dt, max_angle, dv, angle, rate);
            const float4 faded =
                faded_state(b, pc, k, model_chain, pc.wind_slot, make_float4(angle[0], angle[1], rate[0], rate[1]));
            const Mat3 local = local_transform(b, pc, k, model_chain, parent < 0, make_float2(faded.x, faded.y));
            // Every load above before the first store, so that none waits behind one.
            store_motion(b, pc, chain, motion);
            store_mat3(b.chain_local, chain, local);
            b.chain_state[chain] = faded;
        }
        sweep_barrier();
        begin = end;
    }
}

}  // namespace hmsm::detail::cuda
