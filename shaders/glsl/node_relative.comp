#version 450
// Pass 4: each node's position relative to its chain's origin, u_n = R_owner l_n
// (src/cpu/node_relative.cpp).
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

void main() {
    load_constants();
    uint i = thread_index();
    if (i >= pc.element_count) return;
    uint k = i / pc.model_node_count;
    if (instance_paused(k)) return;
    uint n = i % pc.model_node_count;
    uint owner = uint(node_owner[pc.model_node_begin + n]);
    vec3 local = node_local[pc.model_node_begin + n].xyz;
    // The node pair (path walk): node_world follows in the same dispatch (node_world.comp) with u in hand, which
    // is not stored, and the pose is the joint matrix (src/pass_table.h walk_reads, walk_writes).
    if (pc.kind == HMSM_DISPATCH_NODE_PAIR) {
        mat3x4 j = joint_matrix[state_chain(k, owner)];
        node_world[state_node(k, n)] = vec4(joint_origin(j) + joint_rotation(j) * local, 1.0);
        return;
    }
    mat3 r = as_mat3(chain_rotation[half_offset(pc.src_half) + state_chain(k, owner)]);
    node_relative[state_node(k, n)] = vec4(r * local, 0.0);
}
