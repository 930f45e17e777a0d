// The device-side vocabulary of the pass kernels: loads that go through the read-only cache, a
// few float3 / float4 operations, 3x3 matrices stored as three float4 columns, a chain's pose
// from its joint matrix, and the per-element indexing of gpu_layout.h (paused instances,
// ping-pong halves, the chains of a depth level).
//
// Everything here is __host__ __device__ so that the same per-element code also runs on the
// host (emulate_NAME in launchers.h). Within one dispatch no element is both read and written
// (ping-pong halves, one depth level per dispatch), so every load may use the read-only path,
// except in the in-dispatch pointer-jumping rounds, where a block reads what it wrote in its
// previous round (load_mat3_written_in_block), and in the instance sweeps (articulated_math.cuh).
#pragma once

#include "launchers.h"

#include "../../src/common/element_index.h"  // Element, element_of, state_chain, state_node
#include "../../src/common/wind_profile.h"  // HMSM_HOST_DEVICE, wind_profile_y

#include <cstdint>

namespace hmsm::detail::cuda {
template <class T>
HMSM_HOST_DEVICE T load(const T* p) {
#ifdef __CUDA_ARCH__
    return __ldg(p);
#else
    return *p;
#endif
}

HMSM_HOST_DEVICE float3 xyz(float4 v) { return make_float3(v.x, v.y, v.z); }
HMSM_HOST_DEVICE float4 with_w(float3 v, float w) { return make_float4(v.x, v.y, v.z, w); }
HMSM_HOST_DEVICE float3 operator+(float3 a, float3 b) { return make_float3(a.x + b.x, a.y + b.y, a.z + b.z); }
HMSM_HOST_DEVICE float4 operator+(float4 a, float4 b) {
    return make_float4(a.x + b.x, a.y + b.y, a.z + b.z, a.w + b.w);
}
HMSM_HOST_DEVICE float3 operator*(float s, float3 v) { return make_float3(s * v.x, s * v.y, s * v.z); }
HMSM_HOST_DEVICE float dot(float3 a, float3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

/// A 3x3 matrix by columns; acts on column vectors (docs/model.md 3).
struct Mat3 {
    float3 c0, c1, c2;
};

HMSM_HOST_DEVICE float3 operator*(const Mat3& m, float3 v) { return v.x * m.c0 + v.y * m.c1 + v.z * m.c2; }
HMSM_HOST_DEVICE Mat3 operator*(const Mat3& a, const Mat3& b) { return {a * b.c0, a * b.c1, a * b.c2}; }
/// m^T v: the components of v in the frame whose axes are m's columns.
HMSM_HOST_DEVICE float3 transpose_times(const Mat3& m, float3 v) {
    return make_float3(dot(m.c0, v), dot(m.c1, v), dot(m.c2, v));
}

/// Matrix element `index` of a mat3x4 buffer.
HMSM_HOST_DEVICE Mat3 load_mat3(const float4* buffer, uint64_t index) {
    const float4* p = buffer + 3 * index;
    return {xyz(load(p)), xyz(load(p + 1)), xyz(load(p + 2))};
}
/// The same for data written earlier in the same dispatch by another thread of the block (the
/// in-dispatch pointer-jumping rounds): a plain load, which __syncthreads() makes see the
/// block's earlier writes, where the read-only path would not.
HMSM_HOST_DEVICE Mat3 load_mat3_written_in_block(const float4* buffer, uint64_t index) {
    const float4* p = buffer + 3 * index;
    return {xyz(p[0]), xyz(p[1]), xyz(p[2])};
}
/// Stores with w = 0 in every column, as read() reports it.
HMSM_HOST_DEVICE void store_mat3(float4* buffer, uint64_t index, const Mat3& m) {
    float4* p = buffer + 3 * index;
    p[0] = with_w(m.c0, 0.0f);
    p[1] = with_w(m.c1, 0.0f);
    p[2] = with_w(m.c2, 0.0f);
}

/// The pose of state chain `chain` as its joint matrix holds it (rows: R row i, O_i; written by
/// pass 5 in every composition): R by columns and O, the floats stored.
struct Pose {
    Mat3 rotation;
    float3 origin;
};
HMSM_HOST_DEVICE Pose load_joint(const BufferPointers& b, uint64_t chain) {
    const float4* row = b.joint_matrix + 3 * chain;
    const float4 r0 = load(row), r1 = load(row + 1), r2 = load(row + 2);
    return {{make_float3(r0.x, r1.x, r2.x), make_float3(r0.y, r1.y, r2.y), make_float3(r0.z, r1.z, r2.z)},
            make_float3(r0.w, r1.w, r2.w)};
}

/// Whether group instance k is paused (inactive, frozen: docs/model.md 3.9). A dispatch may cover
/// paused instances between active ones (live_control.cpp; it says so in params.w); it skips
/// their elements, writing nothing of theirs. The flag is the z of the instance's first
/// instance_wind element.
HMSM_HOST_DEVICE bool instance_paused(const BufferPointers& b, const gpu::PassConstants& pc, uint32_t k) {
    return pc.params.w != 0.0f &&
           load(b.instance_wind + uint64_t(HMSM_INSTANCE_WIND_VEC4S) * (pc.instance_begin + k)).z != 0.0f;
}

/// First element of ping-pong half `half` of a chain_halves buffer.
HMSM_HOST_DEVICE uint64_t half_begin(const gpu::PassConstants& pc, uint32_t half) {
    return uint64_t(half) * pc.total_chains;
}
/// The chain thread i of a level-by-level dispatch (compose, root_positions) handles: group
/// instance, model chain of the dispatch's level, its parent (-1 for a root) and its state
/// index; the pass writes it in place in the pose half dst (an element offset).
struct LevelChain {
    uint32_t instance;
    int32_t c;
    int32_t parent;
    uint64_t chain;
    uint64_t dst;
};
HMSM_HOST_DEVICE LevelChain level_chain(const BufferPointers& b, const gpu::PassConstants& pc, uint32_t i) {
    const Element e = element_of(i, pc.level_count);
    const int32_t c = int32_t(pc.level_begin + e.index);
    return {e.instance, c, load(b.chain_parent + pc.model_chain_begin + c), state_chain(pc, e.instance, c),
            half_begin(pc, pc.dst_half)};
}

}  // namespace hmsm::detail::cuda
