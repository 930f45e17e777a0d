#version 450
// Pass 6: world positions W_n = O_owner + u_n (src/cpu/node_world.cpp).
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
    uint node = state_node(k, n);
    vec4 w = chain_origin[half_offset(pc.src_half) + state_chain(k, owner)] + node_relative[node];
    node_world[node] = vec4(w.xyz, 1.0);
}
