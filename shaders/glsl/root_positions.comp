#version 450
// Pass 5: chain origins O_c = O_parent + u_attach(c), O_trunk = instance origin
// (src/cpu/root_positions.cpp). Pointer jumping adds the partial sum held by the 2^round-th
// ancestor (round 0 starts from each chain's own offset), half src_half -> half dst_half;
// in-dispatch mode: workgroup k runs every round for group instance k, a barrier between
// rounds. Level by level: one depth per dispatch, in place in half dst_half.
// Wherever O_c is written, the joint matrix [R_c | O_c] is written too, R_c from the same half
// (compose left the final R there): level by level and the last in-dispatch round write final
// values once; per-round dispatches write in every round and the last round (the final half)
// leaves the final matrices.
#extension GL_GOOGLE_include_directive : require
#define HMSM_SPECIALIZED_WORKGROUP_SIZE
#define HMSM_POSE_COHERENCE coherent
#include "common.glsl"

/// The offset chain c of group instance k contributes on its own: the instance origin for the
/// trunk, else the attach node's position relative to the parent chain's origin.
vec4 own_offset(uint k, uint c) {
    if (chain_parent[pc.model_chain_begin + c] < 0)
        return vec4(instance_origin[pc.instance_begin + k].xyz, 0.0);
    return node_relative[state_node(k, uint(chain_attach[pc.model_chain_begin + c]))];
}

vec4 sum_so_far(uint k, uint c, uint round, uint src_half) {
    return round == 0u ? own_offset(k, c) : chain_origin[half_offset(src_half) + state_chain(k, c)];
}

/// Joint matrix of state chain `chain`: rows (R row i, O_i), R from half `pose_half`.
void store_joint(uint chain, uint pose_half, vec4 origin) {
    mat3x4 r = chain_rotation[half_offset(pose_half) + chain];  // three columns (w = 0)
    joint_matrix[chain] = mat3x4(vec4(r[0].x, r[1].x, r[2].x, origin.x),
                                 vec4(r[0].y, r[1].y, r[2].y, origin.y),
                                 vec4(r[0].z, r[1].z, r[2].z, origin.z));
}

/// One pointer-jumping round for model chain c of group instance k.
void jump(uint k, uint c, uint round, uint src_half, uint dst_half, bool write_joint) {
    int ancestor = chain_jump[round * pc.total_model_chains + pc.model_chain_begin + c];
    vec4 origin = sum_so_far(k, c, round, src_half);
    if (ancestor >= 0) origin += sum_so_far(k, uint(ancestor), round, src_half);
    chain_origin[half_offset(dst_half) + state_chain(k, c)] = origin;
    if (write_joint) store_joint(state_chain(k, c), dst_half, origin);
}

void main() {
    if (pc.mode == HMSM_MODE_POINTER_JUMPING_IN_DISPATCH) {
        uint k = workgroup_index();
        if (k >= pc.element_count / pc.model_chain_count) return;  // uniform per workgroup
        for (uint round = 0u; round < pc.round; ++round) {
            for (uint c = gl_LocalInvocationID.x; c < pc.model_chain_count; c += gl_WorkGroupSize.x)
                jump(k, c, round, HMSM_HALF_READ(round), HMSM_HALF_WRITTEN(round), round + 1u == pc.round);
            memoryBarrierBuffer();
            barrier();
        }
        return;
    }
    uint i = thread_index();
    if (i >= pc.element_count) return;
    if (pc.mode == HMSM_MODE_LEVEL_BY_LEVEL) {
        uint dst = half_offset(pc.dst_half);
        uint k = i / pc.level_count;
        uint c = pc.level_begin + i % pc.level_count;
        int parent = chain_parent[pc.model_chain_begin + c];
        vec4 origin = own_offset(k, c);
        if (parent >= 0) origin += chain_origin[dst + state_chain(k, uint(parent))];
        chain_origin[dst + state_chain(k, c)] = origin;
        store_joint(state_chain(k, c), pc.dst_half, origin);
        return;
    }
    jump(i / pc.model_chain_count, i % pc.model_chain_count, pc.round, pc.src_half, pc.dst_half, true);
}
