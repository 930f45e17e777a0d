// The per-chain math of passes 1, 2, 3 and 5, written once for the separate pass kernels
// (wind_force.cu, integrate.cu, compose.cu, root_positions.cu) and the path walk (compose.cu,
// Composition::path_walk). Mirrors src/cpu/NAME.cpp and shaders/glsl/chain_math.glsl.
//
// Loads of state that a block may have written earlier in the same kernel are plain loads
// (which __syncthreads() orders), never the read-only path: kWrittenInBlock marks the
// ping-pong halves of in-dispatch rounds.
#pragma once

#include "coupled_math.cuh"
#include "pass_math.cuh"
#include "../../src/common/fade_math.h"

#include <cmath>

namespace hmsm::detail::cuda {

/// The profile value Y(tau + phi_i) of group instance k at wind-table step slot `step_slot`,
/// `own` its first instance_wind element (lambda, phi mod 2, paused, 0): with lambda, the part
/// of pass 1 that depends only on the instance and the step.
HMSM_HOST_DEVICE float instance_wind_y(const BufferPointers& b, const gpu::PassConstants& pc, uint32_t k,
                                       uint32_t step_slot, float4 own) {
    const float4* table = b.wind_table;
    const uint32_t slot = HMSM_WIND_STEPS + HMSM_WIND_STEP_VEC4S * step_slot;
    const float4* instance = b.instance_wind + uint64_t(HMSM_INSTANCE_WIND_VEC4S) * (pc.instance_begin + k);
    if (pc.profile == HMSM_WIND_PROFILE_TURBULENT)
        return turbulent_y<float>(&table[HMSM_WIND_AMPLITUDES].x, &table[slot + 1].x, &instance[1].x);
    return wind_profile_y<float>(pc.profile, load(table + slot).x + own.y);  // tau + phi, both mod 2
}

/// The wind w_loc = R^T w in the frame `rotation` of a chain whose origin is x: the instance's
/// wind `instance_wind` = lambda_i s Y d (atmospheric: lambda_i s (e_x (1 + u') + e_y v' + e_z w'))
/// plus the force fields at x.
HMSM_HOST_DEVICE float3 chain_local_wind(const BufferPointers& b, float3 x, const Mat3& rotation,
                                         float3 instance_wind) {
    const float4* table = b.wind_table;
    const float4 vector_count = load(table + HMSM_WIND_VECTOR);  // (s d, number of fields)
    float3 wind = instance_wind;
    const uint32_t fields = uint32_t(vector_count.w);
    for (uint32_t f = 0; f < fields; ++f) {
        const float4 sphere = load(table + HMSM_WIND_FIELDS + 2 * f);
        const float4 force = load(table + HMSM_WIND_FIELDS + 2 * f + 1);
        const float3 offset = make_float3(x.x - sphere.x, x.y - sphere.y, x.z - sphere.z);
        const float distance = sqrtf(dot(offset, offset));
        const float reach = fmaxf(0.0f, 1.0f - distance / sphere.w);
        if (!(reach > 0.0f)) continue;  // outside the sphere: no contribution at all (never 0 * F)
        const float h = reach * reach;
        if (force.w == 0.0f) wind = wind + h * xyz(force);
        else if (distance >= 1e-9f) wind = wind + (h * force.x / distance) * offset;
    }
    return transpose_times(rotation, wind);
}

/// Pass 1 of the paper's dynamics for model chain c with the instance's wind in hand:
/// g = A (w_loc.z, -w_loc.x).
HMSM_HOST_DEVICE float2 chain_wind_force_at(const BufferPointers& b, const gpu::PassConstants& pc, uint32_t c,
                                            float3 x, const Mat3& rotation, float3 instance_wind) {
    const float3 local = chain_local_wind(b, x, rotation, instance_wind);
    const float area = load(b.chain_constants + pc.model_chain_begin + c).w;
    return make_float2(area * local.z, -area * local.x);
}

/// The wind scale lambda_i Y(tau + phi_i) of group instance k at step slot `step_slot`.
HMSM_HOST_DEVICE float instance_wind_scale(const BufferPointers& b, const gpu::PassConstants& pc, uint32_t k,
                                           uint32_t step_slot) {
    const float4 own = load(b.instance_wind + uint64_t(HMSM_INSTANCE_WIND_VEC4S) * (pc.instance_begin + k));
    return own.x * instance_wind_y(b, pc, k, step_slot, own);
}

/// The instance's wind vector at step slot `step_slot`: lambda_i Y s d, or for the atmospheric
/// profile lambda_i s (e_x (1 + u') + e_y v' + e_z w') (docs/model.md 3.5).
HMSM_HOST_DEVICE float3 instance_wind_vector(const BufferPointers& b, const gpu::PassConstants& pc, uint32_t k,
                                             uint32_t step_slot) {
    const float4* table = b.wind_table;
    if (pc.profile == HMSM_WIND_PROFILE_ATMOSPHERIC) {
        const uint64_t first = uint64_t(HMSM_INSTANCE_WIND_VEC4S) * (pc.instance_begin + k);
        const uint32_t slot = HMSM_WIND_STEPS + HMSM_WIND_STEP_VEC4S * step_slot;
        const WindComponents<float> c = atmospheric_components<float>(
            &table[HMSM_WIND_AMPLITUDES].x, &table[slot + 1].x, &b.instance_wind[first + 1].x);
        const float scale = load(b.instance_wind + first).x;  // lambda
        return scale * (c.along * xyz(load(table + HMSM_WIND_VECTOR)) + c.lateral * xyz(load(table + HMSM_WIND_LATERAL)) +
                        c.vertical * xyz(load(table + HMSM_WIND_VERTICAL)));
    }
    return instance_wind_scale(b, pc, k, step_slot) * xyz(load(table + HMSM_WIND_VECTOR));
}

/// Pass 1 for model chain c of group instance k: the generalized force g = A (w_loc.z, -w_loc.x)
/// with w_loc = R^T w in the chain's frame of the previous step (R, and the origin x at which
/// the force fields act, loaded by the caller from the pose half), w = lambda_i s Y(tau + phi_i)
/// d plus the force fields; under the coupled dynamics coupled_force's g. pc.wind_slot is the
/// step's slot of the wind table (gpu_layout.h).
HMSM_HOST_DEVICE float2 chain_wind_force(const BufferPointers& b, const gpu::PassConstants& pc,
                                         uint32_t k, uint32_t c, float3 x, const Mat3& rotation) {
    const float3 wind = instance_wind_vector(b, pc, k, pc.wind_slot);
    if (pc.dynamics == HMSM_PASS_DYNAMICS_COUPLED)  // docs/model.md 3.13
        return coupled_force(b, pc, k, state_chain(pc, k, int32_t(c)), c, chain_local_wind(b, x, rotation, wind),
                             load_half_written(b, pc));
    return chain_wind_force_at(b, pc, c, x, rotation, wind);
}

/// Pass 2, the step: symplectic Euler on S = (theta_x, theta_z) of static chain model_chain from
/// state (S, V) under force g, F = g - K S - D V, V += dt/I F, S += dt V, clamped at max_angle
/// (the rate is zeroed at the stop); returns the new (S, V).
HMSM_HOST_DEVICE float4 integrate_step(const BufferPointers& b, const gpu::PassConstants& pc,
                                       uint32_t model_chain, float4 state, float2 g_force) {
    const float4 kc = load(b.chain_constants + model_chain);  // (I, K, D, A)
    const float dt = pc.params.x, max_angle = pc.params.y;
    float angle[2] = {state.x, state.y};
    float rate[2] = {state.z, state.w};
    const float g[2] = {g_force.x, g_force.y};
#pragma unroll
    for (int j = 0; j < 2; ++j) {
        const float f = g[j] - kc.y * angle[j] - kc.z * rate[j];
        rate[j] += dt / kc.x * f;
        angle[j] += dt * rate[j];
        if (fabsf(angle[j]) > max_angle) {
            angle[j] = copysignf(max_angle, angle[j]);
            rate[j] = 0.0f;
        }
    }
    return make_float4(angle[0], angle[1], rate[0], rate[1]);
}

/// The fade of group instance k (docs/model.md 3.12, fading to a coarser level): the state a
/// step of wind-table slot `slot` computed for model chain model_chain, times the step's factor
/// sigma where the instance fades to a level that folds the chain (fade_math.h); else times 1,
/// which leaves every float as it is.
HMSM_HOST_DEVICE float4 faded_state(const BufferPointers& b, const gpu::PassConstants& pc, uint32_t k,
                                    uint32_t model_chain, uint32_t slot, float4 state) {
    const uint32_t word = uint32_t(load(b.instance_wind + uint64_t(HMSM_INSTANCE_WIND_VEC4S) * (pc.instance_begin + k)).w);
    float sigma = 1.0f;
    if (word != 0u && fade_relaxes(word, uint32_t(load(b.chain_rest_rotation + 3 * uint64_t(model_chain)).w)))
        sigma = fade_factor<float>(word, uint32_t(load(b.wind_table + HMSM_WIND_STEPS + HMSM_WIND_STEP_VEC4S * slot).z));
    return make_float4(sigma * state.x, sigma * state.y, sigma * state.z, sigma * state.w);
}

/// The step for state chain `chain` (the paper's or the coupled one), stored to chain_state
/// (theta_x, theta_z, v_x, v_z).
HMSM_HOST_DEVICE void integrate_angles(const BufferPointers& b, const gpu::PassConstants& pc, uint32_t k,
                                       uint32_t model_chain, uint64_t chain, float2 g_force) {
    const float4 state = pc.dynamics == HMSM_PASS_DYNAMICS_COUPLED  // docs/model.md 3.13
                             ? coupled_step(b, pc, model_chain, b.chain_state[chain], g_force)
                             : integrate_step(b, pc, model_chain, b.chain_state[chain], g_force);
    b.chain_state[chain] = faded_state(b, pc, k, model_chain, pc.wind_slot, state);
}

/// Pass 2, the transform: T = Q Rz(theta_z) Rx(theta_x) of static chain model_chain at angles
/// S, with Ry(yaw) of group instance k in front for the trunk (`trunk`: it has no parent).
HMSM_HOST_DEVICE Mat3 local_transform(const BufferPointers& b, const gpu::PassConstants& pc, uint32_t k,
                                      uint32_t model_chain, bool trunk, float2 angle) {
    float sx, cx, sz, cz;
#ifdef __CUDA_ARCH__
    // The hardware sine and cosine: |angle| <= max_angle, where their error is a few 1e-7.
    __sincosf(angle.x, &sx, &cx);
    __sincosf(angle.y, &sz, &cz);
#else
    sincosf(angle.x, &sx, &cx);
    sincosf(angle.y, &sz, &cz);
#endif
    // Rz(theta_z) Rx(theta_x), by columns.
    const Mat3 bend = {make_float3(cz, sz, 0.0f), make_float3(-sz * cx, cz * cx, sx),
                       make_float3(sz * sx, -cz * sx, cx)};
    Mat3 local = load_mat3(b.chain_rest_rotation, model_chain) * bend;
    if (trunk) {
        const float4 yaw = load(b.instance_yaw + pc.instance_begin + k);  // (cos, sin)
        const Mat3 ry = {make_float3(yaw.x, 0.0f, -yaw.y), make_float3(0.0f, 1.0f, 0.0f),
                         make_float3(yaw.y, 0.0f, yaw.x)};
        local = ry * local;
    }
    return local;
}

/// Pass 2 for model chain c of group instance k (state chain `chain`) under force g: the step,
/// then T. T's static inputs are loaded before the state is stored (no store between the loads).
HMSM_HOST_DEVICE Mat3 chain_integrate(const BufferPointers& b, const gpu::PassConstants& pc,
                                      uint32_t k, uint32_t c, uint64_t chain, float2 g_force) {
    const uint32_t model_chain = pc.model_chain_begin + c;
    const bool coupled = pc.dynamics == HMSM_PASS_DYNAMICS_COUPLED;  // docs/model.md 3.13
    const float4 state = faded_state(b, pc, k, model_chain, pc.wind_slot,
                                     coupled ? coupled_step(b, pc, model_chain, b.chain_state[chain], g_force)
                                             : integrate_step(b, pc, model_chain, b.chain_state[chain], g_force));
    const Mat3 local =
        local_transform(b, pc, k, model_chain, load(b.chain_parent + model_chain) < 0, make_float2(state.x, state.y));
    b.chain_state[chain] = state;
    return local;
}

/// One pass-3 pointer-jumping round for model chain c of group instance k in device memory:
/// P = P(2^round-th ancestor) P, half src_half -> half dst_half (round 0 starts from T).
template <bool kWrittenInBlock>
HMSM_HOST_DEVICE void compose_jump(const BufferPointers& b, const gpu::PassConstants& pc, uint32_t k,
                                   uint32_t c, uint32_t round, uint32_t src_half, uint32_t dst_half) {
    const uint64_t chain = state_chain(pc, k, int32_t(c));
    const int32_t ancestor =
        load(b.chain_jump + uint64_t(round) * pc.total_model_chains + pc.model_chain_begin + c);
    // The product accumulated so far: T itself before round 0, else the src half.
    auto product_so_far = [&](uint64_t state) {
        if (round == 0) return load_mat3(b.chain_local, state);
        const uint64_t at = half_begin(pc, src_half) + state;
        return kWrittenInBlock ? load_mat3_written_in_block(b.chain_rotation, at)
                               : load_mat3(b.chain_rotation, at);
    };
    Mat3 rotation = product_so_far(chain);
    if (ancestor >= 0) rotation = product_so_far(state_chain(pc, k, ancestor)) * rotation;
    store_mat3(b.chain_rotation, half_begin(pc, dst_half) + chain, rotation);
}

/// Pass 5: what chain c of group instance k contributes on its own: the instance origin for the
/// trunk, else its attach node's position relative to the parent chain's origin.
HMSM_HOST_DEVICE float4 own_offset(const BufferPointers& b, const gpu::PassConstants& pc, uint32_t k,
                                   int32_t c) {
    if (load(b.chain_parent + pc.model_chain_begin + c) < 0) {
        const float4 origin = load(b.instance_origin + pc.instance_begin + k);
        return make_float4(origin.x, origin.y, origin.z, 0.0f);
    }
    const float4* u = b.node_relative + state_node(pc, k, load(b.chain_attach + pc.model_chain_begin + c));
    return load(u);
}

/// Joint matrix of state chain `chain` (gpu_layout.h): rows (R row i, O_i).
HMSM_HOST_DEVICE void store_joint_of(const BufferPointers& b, uint64_t chain, const Mat3& r, float4 o) {
    float4* row = b.joint_matrix + 3 * chain;
    row[0] = make_float4(r.c0.x, r.c1.x, r.c2.x, o.x);
    row[1] = make_float4(r.c0.y, r.c1.y, r.c2.y, o.y);
    row[2] = make_float4(r.c0.z, r.c1.z, r.c2.z, o.z);
}

/// The same with R from `pose_half` of chain_rotation.
HMSM_HOST_DEVICE void store_joint(const BufferPointers& b, const gpu::PassConstants& pc, uint64_t chain,
                                  uint32_t pose_half, float4 o) {
    store_joint_of(b, chain, load_mat3(b.chain_rotation, half_begin(pc, pose_half) + chain), o);
}

/// One pass-5 pointer-jumping round for model chain c of group instance k in device memory:
/// the partial sum of the 2^round-th ancestor added, src_half -> dst_half, round 0 starting
/// from each chain's own offset; the joint matrix too where `write_joint`.
template <bool kWrittenInBlock>
HMSM_HOST_DEVICE void root_jump(const BufferPointers& b, const gpu::PassConstants& pc, uint32_t k,
                                int32_t c, uint32_t round, uint32_t src_half, uint32_t dst_half,
                                bool write_joint) {
    const int32_t ancestor =
        load(b.chain_jump + uint64_t(round) * pc.total_model_chains + pc.model_chain_begin + c);
    const uint64_t src = half_begin(pc, src_half);
    auto sum_so_far = [&](int32_t chain) {
        if (round == 0) return own_offset(b, pc, k, chain);
        const float4* at = b.chain_origin + src + state_chain(pc, k, chain);
        return kWrittenInBlock ? *at : load(at);
    };
    float4 origin = sum_so_far(c);
    if (ancestor >= 0) origin = origin + sum_so_far(ancestor);
    b.chain_origin[half_begin(pc, dst_half) + state_chain(pc, k, c)] = origin;
    if (write_joint) store_joint(b, pc, state_chain(pc, k, c), dst_half, origin);
}

/// The chain `up` depth levels above model chain c, through the 2^round-th ancestors.
HMSM_HOST_DEVICE int32_t ancestor_above(const BufferPointers& b, const gpu::PassConstants& pc, int32_t c,
                                        uint32_t up) {
    for (uint32_t round = 0; up != 0; ++round, up >>= 1)
        if (up & 1u) c = load(b.chain_jump + uint64_t(round) * pc.total_model_chains + pc.model_chain_begin + c);
    return c;
}

/// The walk record of model chain c (gpu_layout.h), read whole in one round of loads.
struct WalkRecord {
    int32_t words[HMSM_WALK_RECORD_INTS];
};
HMSM_HOST_DEVICE WalkRecord load_walk_record(const BufferPointers& b, const gpu::PassConstants& pc, int32_t c) {
    WalkRecord record;
    const int32_t* first = b.chain_walk + uint64_t(HMSM_WALK_RECORD_INTS) * (pc.model_chain_begin + uint32_t(c));
    const int4* words = reinterpret_cast<const int4*>(first);
#pragma unroll
    for (uint32_t q = 0; q < HMSM_WALK_RECORD_INTS / 4; ++q) {
        const int4 w = load(words + q);
        record.words[4 * q] = w.x;
        record.words[4 * q + 1] = w.y;
        record.words[4 * q + 2] = w.z;
        record.words[4 * q + 3] = w.w;
    }
    return record;
}

/// The static rows a walk from `record` reads for each chain on its path (the rest rotation
/// Q) and each attach node (l_attach) asked into L1 ahead of the walk: the walk kernel issues
/// them before it waits for the pass before, whose end their latency then overlaps.
HMSM_HOST_DEVICE void prefetch_walk(const BufferPointers& b, const gpu::PassConstants& pc, int32_t c,
                                    const WalkRecord& record) {
#ifdef __CUDA_ARCH__
    const uint32_t depth = uint32_t(record.words[0]);
    for (uint32_t up = 0; up <= depth && up < HMSM_WALK_ATTACH_CAPACITY; ++up) {
        const int32_t x = up == 0 ? c : record.words[up];
        prefetch_l1(b.chain_rest_rotation + 3 * uint64_t(pc.model_chain_begin + uint32_t(x)));
        if (up < depth) prefetch_l1(b.node_local + pc.model_node_begin + record.words[HMSM_WALK_ATTACH(up)]);
    }
#else
    (void)b, (void)pc, (void)c, (void)record;
#endif
}

/// Composition::path_walk, passes 3 and 5 for model chain c of group instance k: its ancestors
/// from the trunk down, R = R_parent T and O = O_parent + R_parent l_attach (level by level's
/// operations in its order), each T computed from the chain's new angles as integrate computes
/// it (a walk step stores no T); the pose to `rotation` and `origin` (src/cpu/path_walk.cpp).
/// kFromRecords (a scene of one active instance, latency-bound): the ancestors and their attach
/// nodes from c's walk record `from` (load_walk_record). Else (a forest, where 128 bytes per
/// thread would cost more than the dependent loads, which other warps hide): the ancestors
/// gathered by following chain_parent up, the attach nodes looked up level by level.
/// kFromTopPoses (HMSM_DISPATCH_WALK_AHEAD): the walk starts from the pose of c's nearest ancestor
/// among the top poses (c's own if it is one of them: the first pc.level_count model chains) as
/// the HMSM_DISPATCH_WALK_TOP_POSES dispatch stored it in half src_half, following chain_parent
/// only up to it: the same operations on the same values, so the same pose bit for bit.
template <bool kFromRecords, bool kFromTopPoses = false>
HMSM_HOST_DEVICE void walk_pose(const BufferPointers& b, const gpu::PassConstants& pc, uint32_t k, int32_t c,
                                const WalkRecord* from, Mat3& rotation, float4& origin) {
    int32_t record[kFromRecords ? HMSM_WALK_RECORD_INTS : HMSM_WALK_PATH_CAPACITY + 1];
    if constexpr (kFromRecords) {
        const WalkRecord loaded = from ? *from : load_walk_record(b, pc, c);
#pragma unroll
        for (uint32_t q = 0; q < HMSM_WALK_RECORD_INTS; ++q) record[q] = loaded.words[q];
    } else {
        // record[0]: the levels from the walk's first pose down to c (from the trunk: c's depth).
        const int32_t* parent = b.chain_parent + pc.model_chain_begin;
        const int32_t top_poses = kFromTopPoses ? int32_t(pc.level_count) : 0;
        uint32_t up = 0;
        for (int32_t a = c < top_poses ? -1 : load(parent + c); a >= 0; a = a < top_poses ? -1 : load(parent + a))
            if (++up <= HMSM_WALK_PATH_CAPACITY) record[up] = a;
        record[0] = int32_t(up);
    }
    const uint32_t depth = uint32_t(record[0]);
    auto ancestor = [&](uint32_t up) {
        if (up == 0) return c;
        return up <= HMSM_WALK_PATH_CAPACITY ? record[up] : ancestor_above(b, pc, c, up);
    };
    auto attach = [&](uint32_t up) {
        if constexpr (kFromRecords) {
            if (up < HMSM_WALK_ATTACH_CAPACITY) return record[HMSM_WALK_ATTACH(up)];
        }
        return load(b.chain_attach + pc.model_chain_begin + ancestor(up));
    };
    auto local_of = [&](int32_t x, bool trunk) {
        const float4 state = load(b.chain_state + state_chain(pc, k, x));
        return local_transform(b, pc, k, pc.model_chain_begin + uint32_t(x), trunk, make_float2(state.x, state.y));
    };
    if constexpr (kFromTopPoses) {
        const uint64_t top = half_begin(pc, pc.src_half) + state_chain(pc, k, ancestor(depth));
        rotation = load_mat3(b.chain_rotation, top);
        const float4 o = load(b.chain_origin + top);
        origin = make_float4(o.x, o.y, o.z, 0.0f);
    } else {
        rotation = local_of(ancestor(depth), true);
        const float4 o = load(b.instance_origin + pc.instance_begin + k);
        origin = make_float4(o.x, o.y, o.z, 0.0f);
    }
    // Unrolled so that the loads of several levels are in flight together (they do not depend
    // on the products); the products stay in level order.
#pragma unroll 4
    for (uint32_t level = 1; level <= depth; ++level) {
        const int32_t x = ancestor(depth - level);
        const float3 local = xyz(load(b.node_local + pc.model_node_begin + attach(depth - level)));
        origin = origin + with_w(rotation * local, 0.0f);
        rotation = rotation * local_of(x, false);
    }
}

/// The path walk of chain c of group instance k with its pose stored to the joint matrix.
template <bool kFromRecords>
HMSM_HOST_DEVICE void path_walk(const BufferPointers& b, const gpu::PassConstants& pc, uint32_t k, int32_t c,
                                const WalkRecord* from = nullptr) {
    Mat3 rotation;
    float4 origin;
    walk_pose<kFromRecords>(b, pc, k, c, from, rotation, origin);
    store_joint_of(b, state_chain(pc, k, c), rotation, origin);
}

/// HMSM_DISPATCH_WALK_TOP_POSES for chain c (one of the first pc.level_count: depth at most the top
/// depth, step_program.h walk_top_depth) of group instance k: its pose to half
/// src_half of chain_rotation and chain_origin; the trunk's origin carries in w the wind scale
/// lambda_i Y of the next step (wind-table slot wind_slot + 1) for the walk that integrates ahead.
HMSM_HOST_DEVICE void walk_top_pose(const BufferPointers& b, const gpu::PassConstants& pc, uint32_t k, int32_t c) {
    Mat3 rotation;
    float4 origin;
    walk_pose<false>(b, pc, k, c, nullptr, rotation, origin);
    const uint64_t at = half_begin(pc, pc.src_half) + state_chain(pc, k, c);
    store_mat3(b.chain_rotation, at, rotation);
    const uint32_t slot = pc.wind_slot;
    const uint32_t next_slot = slot + 1u < HMSM_WIND_STEP_SLOTS ? slot + 1u : slot;
    origin.w = c == 0 ? instance_wind_scale(b, pc, k, next_slot) : 0.0f;  // chain 0: the trunk
    b.chain_origin[at] = origin;
}

/// HMSM_DISPATCH_WALK_AHEAD for chain c of group instance k: the path walk from the top poses, its pose
/// to the joint matrix, then the next step's pass 1 at that pose (what the next step's
/// wind_force would read back from the joint matrix, with the trunk's stored wind scale) and
/// pass 2's integration, the new angles to chain_state_next; under the coupled dynamics its
/// pass 1 reads this step's loads and writes the next step's half.
HMSM_HOST_DEVICE void walk_ahead(const BufferPointers& b, const gpu::PassConstants& pc, uint32_t k, int32_t c) {
    Mat3 rotation;
    float4 origin;
    walk_pose<false, true>(b, pc, k, c, nullptr, rotation, origin);
    const uint64_t chain = state_chain(pc, k, c);
    store_joint_of(b, chain, rotation, origin);
    // The atmospheric wind is a vector, not a stored scale times s d: evaluated here.
    float3 wind;
    if (pc.profile == HMSM_WIND_PROFILE_ATMOSPHERIC) {
        const uint32_t next_slot = pc.wind_slot + 1u < HMSM_WIND_STEP_SLOTS ? pc.wind_slot + 1u : pc.wind_slot;
        wind = instance_wind_vector(b, pc, k, next_slot);
    } else {
        const float scale = load(b.chain_origin + half_begin(pc, pc.src_half) + state_chain(pc, k, 0)).w;
        wind = scale * xyz(load(b.wind_table + HMSM_WIND_VECTOR));
    }
    const uint32_t model_chain = pc.model_chain_begin + uint32_t(c);
    // The next step's slot, which its fade factor reads (a run leaves it for the step after).
    const uint32_t ahead_slot = pc.wind_slot + 1u < HMSM_WIND_STEP_SLOTS ? pc.wind_slot + 1u : pc.wind_slot;
    if (pc.dynamics == HMSM_PASS_DYNAMICS_COUPLED) {  // the next step writes the other load half
        const float2 g = coupled_force(b, pc, k, chain, uint32_t(c), chain_local_wind(b, xyz(origin), rotation, wind),
                                       1u - load_half_written(b, pc));
        b.chain_state_next[chain] =
            faded_state(b, pc, k, model_chain, ahead_slot, coupled_step(b, pc, model_chain, load(b.chain_state + chain), g));
        return;
    }
    const float2 g = chain_wind_force_at(b, pc, uint32_t(c), xyz(origin), rotation, wind);
    b.chain_state_next[chain] =
        faded_state(b, pc, k, model_chain, ahead_slot, integrate_step(b, pc, model_chain, load(b.chain_state + chain), g));
}

}  // namespace hmsm::detail::cuda
