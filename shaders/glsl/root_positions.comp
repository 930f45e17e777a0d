#version 450
// Pass 5: chain origins O_c = O_parent + u_attach(c), O_trunk = instance origin
// (src/cpu/root_positions.cpp). Pointer jumping adds the partial sum held by the 2^r-th
// ancestor (round 0 starts from each chain's own offset), half src_half -> half dst_half;
// level by level: one depth per dispatch, in place in half dst_half.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

/// The offset chain c of group instance k contributes on its own: the instance origin for the
/// trunk, else the attach node's position relative to the parent chain's origin.
vec4 own_offset(uint k, uint c) {
    if (chain_parent[pc.model_chain_begin + c] < 0)
        return vec4(instance_origin[pc.instance_begin + k].xyz, 0.0);
    return node_relative[state_node(k, uint(chain_attach[pc.model_chain_begin + c]))];
}

vec4 sum_so_far(uint k, uint c) {
    return pc.round == 0u ? own_offset(k, c)
                          : chain_origin[half_offset(pc.src_half) + state_chain(k, c)];
}

void main() {
    uint i = thread_index();
    if (i >= pc.element_count) return;
    uint dst = half_offset(pc.dst_half);
    if (pc.mode == HMSM_MODE_LEVEL_BY_LEVEL) {
        uint k = i / pc.level_count;
        uint c = pc.level_begin + i % pc.level_count;
        int parent = chain_parent[pc.model_chain_begin + c];
        vec4 origin = own_offset(k, c);
        if (parent >= 0) origin += chain_origin[dst + state_chain(k, uint(parent))];
        chain_origin[dst + state_chain(k, c)] = origin;
        return;
    }
    uint k = i / pc.model_chain_count;
    uint c = i % pc.model_chain_count;
    int ancestor = chain_jump[pc.round * pc.total_model_chains + pc.model_chain_begin + c];
    vec4 origin = sum_so_far(k, c);
    if (ancestor >= 0) origin += sum_so_far(k, uint(ancestor));
    chain_origin[dst + state_chain(k, c)] = origin;
}
