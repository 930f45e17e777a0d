// Pass 7: branch-mesh and leaf vertices rigid with their chain, v = O_c + R_c v_local (the pose
// read from the joint matrix [R_c | O_c], which every composition writes); base-ring
// vertices of child chains blend with the parent chain (the paper's contour fix-up) so joints
// stay closed while the child swings. The dispatch kind is the vertex layout (gpu_layout.h):
// CONTOUR_PACKED stores the octahedral normal word in the position's w (src/common/octahedral.h) and no vertex_normal.
#include "cpu_state.h"

#include "../common/octahedral.h"

#include <glm/geometric.hpp>

namespace hmsm::detail::cpu {

template <class T>
void contour(State<T>& s, const gpu::PassConstants& pc, Range r) {
    using vec3 = typename State<T>::vec3;
    const T beta = s.fix_weight;
    for (uint32_t i = r.begin; i < r.end; ++i) {
        Element e = element_of(i, pc.model_vertex_count);
        if (instance_paused(s, pc, e.instance)) continue;
        uint32_t v = pc.model_vertex_begin + e.index;
        glm::ivec2 chains = s.vertex_chain[v];
        const uint64_t own = state_chain(pc, e.instance, chains.x);
        const auto rotation = joint_rotation(s, own);
        vec3 position = joint_origin(s, own) + rotation * vec3(s.vertex_rest_position[v]);
        vec3 normal = rotation * vec3(s.vertex_rest_normal[v]);
        if (chains.y >= 0) {
            const uint64_t parent = state_chain(pc, e.instance, chains.y);
            const auto parent_rotation = joint_rotation(s, parent);
            vec3 p = joint_origin(s, parent) + parent_rotation * vec3(s.vertex_parent_position[v]);
            vec3 n = parent_rotation * vec3(s.vertex_parent_normal[v]);
            position = (T(1) - beta) * position + beta * p;
            normal = glm::normalize((T(1) - beta) * normal + beta * n);
        }
        uint64_t out = pc.vertex_begin + uint64_t(e.instance) * pc.model_vertex_count + e.index;
        if (pc.kind == HMSM_DISPATCH_CONTOUR_PACKED) {
            s.vertex_position[out] = {position, packed_word_to_w<T>(encode_normal_word(normal.x, normal.y, normal.z))};
        } else {
            s.vertex_position[out] = {position, T(1)};
            s.vertex_normal[out] = {normal, T(0)};
        }
    }
}

template void contour<float>(State<float>&, const gpu::PassConstants&, Range);
template void contour<double>(State<double>&, const gpu::PassConstants&, Range);

}  // namespace hmsm::detail::cpu
