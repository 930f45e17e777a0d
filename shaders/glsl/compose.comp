#version 450
// Pass 3: total rotation R_c = R_parent T_c (src/cpu/compose.cpp). Pointer jumping: round r
// multiplies in the product held by the 2^r-th ancestor, reading half src_half and writing
// half dst_half (round 0 reads T), so no thread reads what another writes. Level by level:
// one depth per dispatch, in place in half dst_half.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

/// Product of T over the chains between c and its 2^round-th ancestor (exclusive) so far.
mat3 product_so_far(uint chain) {
    return pc.round == 0u ? as_mat3(chain_local[chain])
                          : as_mat3(chain_rotation[half_offset(pc.src_half) + chain]);
}

void main() {
    uint i = thread_index();
    if (i >= pc.element_count) return;
    uint dst = half_offset(pc.dst_half);
    if (pc.mode == HMSM_MODE_LEVEL_BY_LEVEL) {
        uint k = i / pc.level_count;
        uint c = pc.level_begin + i % pc.level_count;
        int parent = chain_parent[pc.model_chain_begin + c];
        uint chain = state_chain(k, c);
        mat3 t = as_mat3(chain_local[chain]);
        mat3 r = parent < 0 ? t : as_mat3(chain_rotation[dst + state_chain(k, uint(parent))]) * t;
        chain_rotation[dst + chain] = as_mat3x4(r);
        return;
    }
    uint k = i / pc.model_chain_count;
    uint c = i % pc.model_chain_count;
    uint chain = state_chain(k, c);
    int ancestor = chain_jump[pc.round * pc.total_model_chains + pc.model_chain_begin + c];
    mat3 r = ancestor < 0 ? product_so_far(chain)
                          : product_so_far(state_chain(k, uint(ancestor))) * product_so_far(chain);
    chain_rotation[dst + chain] = as_mat3x4(r);
}
