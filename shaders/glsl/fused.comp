#version 450
// Composition::fused: passes 1-5 in one dispatch, workgroup k for group instance k (gpu_layout.h
// HMSM_MODE_FUSED; docs/architecture.md). An instance's passes read only its own chains and
// nodes, so a workgroup barrier between two passes stands in for the dispatch boundary:
//   1+2. wind_force and integrate per chain (chain_math.glsl, the separate passes' math);
//   3.   compose's pointer-jumping rounds, round r reading half HMSM_HALF_READ(r) and writing
//        half HMSM_HALF_WRITTEN(r), as pointer_jumping_in_dispatch;
//   4.   node_relative per node;
//   5.   root_positions' rounds, the last writing O and the joint matrices.
// Shared variant (specialization constant 1, SHARED_FLOATS, covers 18 floats per chain): the
// rounds' two halves live in workgroup shared memory, rotation half h of chain c at
// (h n + c) 9; integrate puts T into the half round 0 reads. The last compose round also writes
// R to the pose half of chain_rotation, node_relative and the joint matrices read R from
// shared memory, and root_positions' two origin halves (3 floats per chain each) reuse the
// rotation half that is not the pose half. Only the pose halves reach device memory. Device
// variant (SHARED_FLOATS = 1): the rounds run in the ping-pong halves of device memory exactly
// as compose.comp and root_positions.comp do in-dispatch.
#extension GL_GOOGLE_include_directive : require
#define HMSM_SPECIALIZED_WORKGROUP_SIZE
#define HMSM_POSE_COHERENCE coherent
#define HMSM_STATE_COHERENCE coherent
#include "common.glsl"
#include "chain_math.glsl"

layout(constant_id = 1) const uint SHARED_FLOATS = 1u;
shared float pool[SHARED_FLOATS];

/// Every write of the workgroup so far (device and shared memory) visible to all of it.
void pass_barrier() {
    memoryBarrierBuffer();
    memoryBarrierShared();
    barrier();
}

uint rotation_at(uint which, uint c) { return (which * pc.model_chain_count + c) * 9u; }
mat3 shared_rotation(uint which, uint c) {
    uint a = rotation_at(which, c);
    return mat3(pool[a], pool[a + 1u], pool[a + 2u], pool[a + 3u], pool[a + 4u], pool[a + 5u],
                pool[a + 6u], pool[a + 7u], pool[a + 8u]);
}
void set_shared_rotation(uint which, uint c, mat3 m) {
    uint a = rotation_at(which, c);
    for (int j = 0; j < 3; ++j) {
        pool[a + 3u * j] = m[j].x;
        pool[a + 3u * j + 1u] = m[j].y;
        pool[a + 3u * j + 2u] = m[j].z;
    }
}
/// Origin half `which` of chain c, in the rotation half other than the pose half.
uint origin_at(uint pose_half, uint which, uint c) {
    return rotation_at(1u - pose_half, 0u) + (which * pc.model_chain_count + c) * 3u;
}
vec4 shared_origin(uint pose_half, uint which, uint c) {
    uint a = origin_at(pose_half, which, c);
    return vec4(pool[a], pool[a + 1u], pool[a + 2u], 0.0);
}
void set_shared_origin(uint pose_half, uint which, uint c, vec4 o) {
    uint a = origin_at(pose_half, which, c);
    pool[a] = o.x;
    pool[a + 1u] = o.y;
    pool[a + 2u] = o.z;
}

void main() {
    uint k = workgroup_index();
    uint n = pc.model_chain_count;
    if (k >= pc.element_count / n || instance_paused(k)) return;  // uniform per workgroup
    uint size = gl_WorkGroupSize.x;
    uint first = gl_LocalInvocationID.x;
    bool in_shared = SHARED_FLOATS >= HMSM_FUSED_SHARED_FLOATS_PER_CHAIN * n;
    uint rounds = pc.round;
    uint pose_half = HMSM_FINAL_HALF(rounds);

    // Passes 1 and 2 (R and O of the previous step from the pose half).
    for (uint c = first; c < n; c += size) {
        uint chain = state_chain(k, c);
        uint pose = half_offset(pc.src_half) + chain;
        vec2 g = chain_wind_force(k, c, chain_origin[pose].xyz, as_mat3(chain_rotation[pose]));
        chain_force[chain] = g;
        mat3 t = chain_integrate(k, c, chain, g);
        chain_local[chain] = as_mat3x4(t);
        if (in_shared) set_shared_rotation(HMSM_HALF_READ(0u), c, t);
    }
    pass_barrier();

    // Pass 3.
    for (uint round = 0u; round < rounds; ++round) {
        uint src = HMSM_HALF_READ(round), dst = HMSM_HALF_WRITTEN(round);
        for (uint c = first; c < n; c += size) {
            if (!in_shared) {
                compose_jump(k, c, round, src, dst);
                continue;
            }
            int ancestor = chain_jump[round * pc.total_model_chains + pc.model_chain_begin + c];
            mat3 r = shared_rotation(src, c);
            if (ancestor >= 0) r = shared_rotation(src, uint(ancestor)) * r;
            set_shared_rotation(dst, c, r);
            if (round + 1u == rounds) chain_rotation[half_offset(dst) + state_chain(k, c)] = as_mat3x4(r);
        }
        pass_barrier();
    }

    // Pass 4.
    for (uint node = first; node < pc.model_node_count; node += size) {
        uint owner = uint(node_owner[pc.model_node_begin + node]);
        mat3 r = in_shared ? shared_rotation(pose_half, owner)
                           : as_mat3(chain_rotation[half_offset(pose_half) + state_chain(k, owner)]);
        node_relative[state_node(k, node)] = vec4(r * node_local[pc.model_node_begin + node].xyz, 0.0);
    }
    pass_barrier();

    // Pass 5.
    for (uint round = 0u; round < rounds; ++round) {
        uint src = HMSM_HALF_READ(round), dst = HMSM_HALF_WRITTEN(round);
        bool last = round + 1u == rounds;
        for (uint c = first; c < n; c += size) {
            if (!in_shared) {
                root_jump(k, c, round, src, dst, last);
                continue;
            }
            int ancestor = chain_jump[round * pc.total_model_chains + pc.model_chain_begin + c];
            vec4 origin = round == 0u ? own_offset(k, c) : shared_origin(pose_half, src, c);
            if (ancestor >= 0)
                origin += round == 0u ? own_offset(k, uint(ancestor)) : shared_origin(pose_half, src, uint(ancestor));
            if (last) {
                uint chain = state_chain(k, c);
                chain_origin[half_offset(dst) + chain] = origin;
                store_joint_of(chain, shared_rotation(pose_half, c), origin);
            } else {
                set_shared_origin(pose_half, dst, c, origin);
            }
        }
        if (!last) pass_barrier();
    }
}
