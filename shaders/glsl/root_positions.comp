#version 450
// Pass 5: chain origins O_c = O_parent + u_attach(c), O_trunk = instance origin
// (src/cpu/root_positions.cpp). Pointer jumping adds the partial sum held by the 2^round-th
// ancestor (round 0 starts from each chain's own offset), half src_half -> half dst_half;
// JUMP_ROUNDS_IN_DISPATCH: workgroup k runs every round for group instance k, a barrier between
// rounds. LEVEL: one depth per dispatch, in place in half dst_half.
// Wherever O_c is written, the joint matrix [R_c | O_c] is written too, R_c from the same half
// (compose left the final R there): level by level and the last in-dispatch round write final
// values once; per-round dispatches write in every round and the last round (the final half)
// leaves the final matrices.
#extension GL_GOOGLE_include_directive : require
#define HMSM_SPECIALIZED_WORKGROUP_SIZE
#define HMSM_POSE_COHERENCE coherent
#include "common.glsl"
#include "chain_math.glsl"  // root_jump, own_offset, store_joint

void main() {
    load_constants();
    if (pc.kind == HMSM_DISPATCH_JUMP_ROUNDS_IN_DISPATCH) {
        uint k = rounds_instance();
        if (k >= pc.element_count / pc.model_chain_count || instance_paused(k)) return;  // uniform per workgroup
        for (uint round = 0u; round < pc.round; ++round) {
            for (uint c = gl_LocalInvocationID.x; c < pc.model_chain_count; c += gl_WorkGroupSize.x)
                root_jump(k, c, round, HMSM_HALF_READ(round), HMSM_HALF_WRITTEN(round), round + 1u == pc.round);
            memoryBarrierBuffer();
            barrier();
        }
        return;
    }
    uint i = thread_index();
    if (i >= pc.element_count) return;
    if (pc.kind == HMSM_DISPATCH_LEVEL) {
        uint dst = half_offset(pc.dst_half);
        uint k = i / pc.level_count;
        if (instance_paused(k)) return;
        uint c = pc.level_begin + i % pc.level_count;
        int parent = chain_parent[pc.model_chain_begin + c];
        vec4 origin = own_offset(k, c);
        if (parent >= 0) origin += chain_origin[dst + state_chain(k, uint(parent))];
        chain_origin[dst + state_chain(k, c)] = origin;
        store_joint(state_chain(k, c), pc.dst_half, origin);
        return;
    }
    if (instance_paused(i / pc.model_chain_count)) return;
    root_jump(i / pc.model_chain_count, i % pc.model_chain_count, pc.round, pc.src_half, pc.dst_half, true);  // JUMP_ROUND
}
