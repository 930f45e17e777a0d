// The branch mesh and leaf cards of pass 7 (docs/model.md 3.8), as a static template in chain-local
// coordinates; the contour pass makes it world-space each step.
#pragma once

#include <hmsm/export.h>

#include <hmsm/hierarchy.h>

#include <cstdint>
#include <vector>

namespace hmsm {

struct MeshVertex {
    int32_t chain = 0;          ///< rigid with this chain
    int32_t fix_chain = -1;     ///< base-ring vertex of a non-trunk chain: the parent chain
    Vec3 position{0.0};   ///< in the chain's rest frame, relative to its attach node
    Vec3 normal{0.0};
    Vec3 parent_position{0.0};  ///< same rest vertex in fix_chain's frame (if any)
    Vec3 parent_normal{0.0};
};

struct MeshTemplate {
    std::vector<MeshVertex> vertices;  ///< per chain (chain order): its rings, then its tip; then leaf cards
    std::vector<uint32_t> indices;     ///< triangles, counter-clockwise seen from outside
    uint32_t ring_vertex_count = 0;
    uint32_t tip_count = 0;
    uint32_t leaf_count = 0;
    uint32_t triangle_count() const { return static_cast<uint32_t>(indices.size() / 3); }
};

/// Vertex count of docs/model.md 3.8: sum over chains of (members+1)*ring_sides + tips + 4*leaves.
HMSM_API uint64_t mesh_vertex_count(const TreeModel& tree, const Hierarchy& hierarchy,
                                    const ModelOptions& options);

HMSM_API MeshTemplate build_mesh(const TreeModel& tree, const Hierarchy& hierarchy,
                                 const ModelOptions& options);

}  // namespace hmsm
