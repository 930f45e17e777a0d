#version 450
// Pass 4: each node's position relative to its chain's origin, u_n = R_owner l_n
// (src/cpu/node_relative.cpp).
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

void main() {
    uint i = thread_index();
    if (i >= pc.element_count) return;
    uint k = i / pc.model_node_count;
    uint n = i % pc.model_node_count;
    uint owner = uint(node_owner[pc.model_node_begin + n]);
    mat3 r = as_mat3(chain_rotation[half_offset(pc.src_half) + state_chain(k, owner)]);
    vec4 u = vec4(r * node_local[pc.model_node_begin + n].xyz, 0.0);
    // Path walk: node_world follows in the same dispatch (node_world.comp) with u in hand, which
    // is not stored (src/pass_table.h walk_writes).
    if (pc.mode == HMSM_MODE_PATH_WALK) {
        vec4 w = chain_origin[half_offset(pc.src_half) + state_chain(k, owner)] + u;
        node_world[state_node(k, n)] = vec4(w.xyz, 1.0);
    } else {
        node_relative[state_node(k, n)] = u;
    }
}
