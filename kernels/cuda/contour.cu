// Pass 7: branch-mesh and leaf vertices rigid with their chain, v = O_c + R_c v_rest, normal
// R_c n_rest. Base-ring vertices of child chains are the paper's contour fix-up: a blend
// (1 - beta) own + beta parent of the same rest vertex carried by the parent chain, normal
// renormalized, so the joint stays closed while the child swings. The largest pass (one thread
// per vertex of every instance): the model-scope inputs are shared by all instances and stay in
// L2, the outputs are written once, coalesced: 32 bytes per thread (position and normal), or 16
// in the packed vertex layout (pc.mode, gpu_layout.h), where the position's w carries the
// octahedral normal word (src/common/octahedral.h) and vertex_normal is not written.
#include "pass_math.cuh"

#include "../../src/common/octahedral.h"

#include <cmath>

namespace hmsm::detail::cuda {

static HMSM_HOST_DEVICE void contour_element(const BufferPointers& b,
                                             const gpu::PassConstants& pc, uint32_t i) {
    const Element e = element_of(i, pc.model_vertex_count);
    const uint32_t v = pc.model_vertex_begin + e.index;
    const uint64_t pose = half_begin(pc, pc.src_half);
    const int2 chains = load(b.vertex_chain + v);  // (own chain, fix-up parent chain or -1)
    const uint64_t own = pose + state_chain(pc, e.instance, chains.x);
    Mat3 rotation = load_mat3(b.chain_rotation, own);
    float3 position = xyz(load(b.chain_origin + own)) + rotation * xyz(load(b.vertex_rest_position + v));
    float3 normal = rotation * xyz(load(b.vertex_rest_normal + v));
    if (chains.y >= 0) {
        const uint64_t parent = pose + state_chain(pc, e.instance, chains.y);
        rotation = load_mat3(b.chain_rotation, parent);
        const float3 p = xyz(load(b.chain_origin + parent)) + rotation * xyz(load(b.vertex_parent_position + v));
        const float3 n = rotation * xyz(load(b.vertex_parent_normal + v));
        const float beta = pc.params.z;
        position = (1.0f - beta) * position + beta * p;
        normal = (1.0f - beta) * normal + beta * n;
        normal = (1.0f / sqrtf(dot(normal, normal))) * normal;
    }
    const uint64_t out = pc.vertex_begin + i;
    if (pc.mode == HMSM_VERTEX_LAYOUT_PACKED) {
        b.vertex_position[out] =
            with_w(position, packed_word_to_w<float>(encode_normal_word(normal.x, normal.y, normal.z)));
    } else {
        b.vertex_position[out] = with_w(position, 1.0f);
        b.vertex_normal[out] = with_w(normal, 0.0f);
    }
}

HMSM_CUDA_PASS(contour)

}  // namespace hmsm::detail::cuda
