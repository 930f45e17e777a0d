#version 450
// Pass 7: branch-mesh and leaf vertices rigid with their chain, v = O_c + R_c v_local. The base
// ring of a child chain blends with the parent chain by fix_weight (the paper's contour fix-up)
// so joints stay closed while the child swings (src/cpu/contour.cpp). pc.mode is the vertex
// layout: separate writes vec4(position, 1) and vec4(normal, 0); packed writes only the position,
// with the octahedral normal word (octahedral.glsl) as its w.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

void main() {
    uint i = thread_index();
    if (i >= pc.element_count) return;
    uint k = i / pc.model_vertex_count;
    uint e = i % pc.model_vertex_count;
    uint v = pc.model_vertex_begin + e;
    uint pose = half_offset(pc.src_half);
    float beta = pc.params.z;
    ivec2 chains = vertex_chain[v];  // (own chain, fix-up parent chain or -1)

    uint own = pose + state_chain(k, uint(chains.x));
    mat3 r = as_mat3(chain_rotation[own]);
    vec3 position = chain_origin[own].xyz + r * vertex_rest_position[v].xyz;
    vec3 normal = r * vertex_rest_normal[v].xyz;
    if (chains.y >= 0) {
        uint parent = pose + state_chain(k, uint(chains.y));
        mat3 rp = as_mat3(chain_rotation[parent]);
        vec3 p = chain_origin[parent].xyz + rp * vertex_parent_position[v].xyz;
        vec3 n = rp * vertex_parent_normal[v].xyz;
        position = (1.0 - beta) * position + beta * p;
        normal = normalize((1.0 - beta) * normal + beta * n);
    }
    uint out_index = pc.vertex_begin + k * pc.model_vertex_count + e;
    if (pc.mode == HMSM_VERTEX_LAYOUT_PACKED) {
        vertex_position[out_index] = vec4(position, uintBitsToFloat(packSnorm2x16(oct_encode(normal))));
    } else {
        vertex_position[out_index] = vec4(position, 1.0);
        vertex_normal[out_index] = vec4(normal, 0.0);
    }
}
