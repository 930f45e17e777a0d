#version 450
// Pass 3: total rotation R_c = R_parent T_c (src/cpu/compose.cpp). Pointer jumping: round r
// multiplies in the product held by the 2^round-th ancestor, reading half src_half and writing
// half dst_half (round 0 reads T), so no thread reads what another writes.
// JUMP_ROUNDS_IN_DISPATCH: workgroup k runs every round for group instance k, a barrier between
// rounds. LEVEL: one depth per dispatch, in place in half dst_half. POSE_WALK and
// POSE_WALK_FROM_RECORDS: passes 3 and 5 together, each chain walking its ancestors from the
// trunk down (chain_math.glsl path_walk). The kinds are gpu_layout.h's HMSM_DISPATCH_*.
#extension GL_GOOGLE_include_directive : require
#define HMSM_SPECIALIZED_WORKGROUP_SIZE
#define HMSM_POSE_COHERENCE coherent
#include "common.glsl"
#include "chain_math.glsl"  // compose_jump

void main() {
    load_constants();
    if (pc.kind == HMSM_DISPATCH_JUMP_ROUNDS_IN_DISPATCH) {
        uint k = rounds_instance();
        if (k >= pc.element_count / pc.model_chain_count || instance_paused(k)) return;  // uniform per workgroup
        for (uint round = 0u; round < pc.round; ++round) {
            for (uint c = gl_LocalInvocationID.x; c < pc.model_chain_count; c += gl_WorkGroupSize.x)
                compose_jump(k, c, round, HMSM_HALF_READ(round), HMSM_HALF_WRITTEN(round));
            memoryBarrierBuffer();
            barrier();
        }
        return;
    }
    uint i = thread_index();
    if (i >= pc.element_count) return;
    if (instance_paused(i / (pc.kind == HMSM_DISPATCH_LEVEL ? pc.level_count : pc.model_chain_count))) return;
    if (pc.kind == HMSM_DISPATCH_POSE_WALK || pc.kind == HMSM_DISPATCH_POSE_WALK_FROM_RECORDS) {
        path_walk(i / pc.model_chain_count, i % pc.model_chain_count);  // and root_positions
        return;
    }
    if (pc.kind == HMSM_DISPATCH_LEVEL) {
        uint dst = half_offset(pc.dst_half);
        uint k = i / pc.level_count;
        uint c = pc.level_begin + i % pc.level_count;
        int parent = chain_parent[pc.model_chain_begin + c];
        uint chain = state_chain(k, c);
        mat3 t = as_mat3(chain_local[chain]);
        mat3 r = parent < 0 ? t : as_mat3(chain_rotation[dst + state_chain(k, uint(parent))]) * t;
        chain_rotation[dst + chain] = as_mat3x4(r);
        return;
    }
    compose_jump(i / pc.model_chain_count, i % pc.model_chain_count, pc.round, pc.src_half, pc.dst_half);  // JUMP_ROUND
}
