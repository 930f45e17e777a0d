#version 450
// Pass 7: branch-mesh and leaf vertices rigid with their chain, v = O_c + R_c v_local, the pose
// read from the joint matrix [R_c | O_c] that pass 5 writes in every composition. The base
// ring of a child chain blends with the parent chain by fix_weight (the paper's contour fix-up)
// so joints stay closed while the child swings (src/cpu/contour.cpp). The dispatch kind is the
// vertex layout: CONTOUR_SEPARATE writes vec4(position, 1) and vec4(normal, 0); CONTOUR_PACKED
// writes only the position, with the octahedral normal word (octahedral.glsl) as its w.
//
// Separate: thread i places element i. Packed: thread w reads the model-scope inputs of model
// vertex w % n once (its chains, rest position and normal) and places that vertex in the
// HMSM_PACKED_CONTOUR_INSTANCES instances of its group w / n (gpu_layout.h; the host launches
// that many threads, backend.h launch_shape).
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

/// Model vertex e (index v of the static arrays) in group instance k; the fix-up's parent copies
/// are read here, where a vertex has them.
void place_vertex(uint k, uint e, uint v, ivec2 chains, vec3 rest_position, vec3 rest_normal) {
    mat3x4 own = joint_matrix[state_chain(k, uint(chains.x))];
    mat3 r = joint_rotation(own);
    vec3 position = joint_origin(own) + r * rest_position;
    vec3 normal = r * rest_normal;
    if (chains.y >= 0) {
        float beta = pc.params.z;
        mat3x4 parent = joint_matrix[state_chain(k, uint(chains.y))];
        mat3 rp = joint_rotation(parent);
        vec3 p = joint_origin(parent) + rp * vertex_parent_position[v].xyz;
        vec3 n = rp * vertex_parent_normal[v].xyz;
        position = (1.0 - beta) * position + beta * p;
        normal = normalize((1.0 - beta) * normal + beta * n);
    }
    uint out_index = pc.vertex_begin + k * pc.model_vertex_count + e;
    if (pc.kind == HMSM_DISPATCH_CONTOUR_PACKED) {
        vertex_position[out_index] = vec4(position, uintBitsToFloat(packSnorm2x16(oct_encode(normal))));
    } else {
        vertex_position[out_index] = vec4(position, 1.0);
        vertex_normal[out_index] = vec4(normal, 0.0);
    }
}

void main() {
    load_constants();
    uint n = pc.model_vertex_count;
    uint w = thread_index();
    if (pc.kind != HMSM_DISPATCH_CONTOUR_PACKED) {
        if (w >= pc.element_count || instance_paused(w / n)) return;
        uint v = pc.model_vertex_begin + w % n;
        place_vertex(w / n, w % n, v, vertex_chain[v], vertex_rest_position[v].xyz, vertex_rest_normal[v].xyz);
        return;
    }
    uint instances = pc.element_count / n;
    if (w >= (instances + HMSM_PACKED_CONTOUR_INSTANCES - 1u) / HMSM_PACKED_CONTOUR_INSTANCES * n) return;
    uint e = w % n;
    uint v = pc.model_vertex_begin + e;
    ivec2 chains = vertex_chain[v];  // (own chain, fix-up parent chain or -1)
    vec3 rest_position = vertex_rest_position[v].xyz;
    vec3 rest_normal = vertex_rest_normal[v].xyz;
    uint first = w / n * HMSM_PACKED_CONTOUR_INSTANCES;
    uint last = min(instances, first + HMSM_PACKED_CONTOUR_INSTANCES);
    for (uint k = first; k < last; ++k)
        if (!instance_paused(k)) place_vertex(k, e, v, chains, rest_position, rest_normal);
}
