// Branch mesh and leaf cards in chain-local rest coordinates (docs/model.md 3.8).
#include <hmsm/mesh.h>

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

#include <cmath>
#include <numbers>

namespace hmsm {

uint64_t mesh_vertex_count(const TreeModel& tree, const Hierarchy& h, const ModelOptions& options) {
    uint64_t count = 4ull * tree.leaves.size();
    for (const Chain& chain : h.chains) {
        count += uint64_t(chain.members.size() + 1) * uint64_t(options.ring_sides);
        if (h.continuation[chain.members.back()] < 0) ++count;  // tip
    }
    return count;
}

namespace {

/// A vertex given in world rest coordinates, expressed in its chain's frame (and, for a
/// fix-up vertex, in the parent chain's frame too).
MeshVertex rigid_vertex(const TreeModel& tree, const Hierarchy& h, int32_t chain,
                        int32_t fix_chain, const glm::dvec3& position, const glm::dvec3& normal) {
    auto local = [&](int32_t c, const glm::dvec3& p) {
        return glm::transpose(h.chains[c].frame) * (p - tree.nodes[h.chains[c].attach_node].position);
    };
    MeshVertex v;
    v.chain = chain;
    v.fix_chain = fix_chain;
    v.position = local(chain, position);
    v.normal = glm::transpose(h.chains[chain].frame) * normal;
    if (fix_chain >= 0) {
        v.parent_position = local(fix_chain, position);
        v.parent_normal = glm::transpose(h.chains[fix_chain].frame) * normal;
    }
    return v;
}

}  // namespace

MeshTemplate build_mesh(const TreeModel& tree, const Hierarchy& h, const ModelOptions& options) {
    MeshTemplate mesh;
    const uint32_t sides = uint32_t(options.ring_sides);
    const auto& nodes = tree.nodes;
    for (size_t c = 0; c < h.chains.size(); ++c) {
        const Chain& chain = h.chains[c];
        std::vector<int32_t> path;  // attach node, then members
        path.push_back(chain.attach_node);
        path.insert(path.end(), chain.members.begin(), chain.members.end());
        const size_t rings = path.size();
        auto segment = [&](size_t j) {  // direction of segment path[j] -> path[j+1]
            return glm::normalize(nodes[path[j + 1]].position - nodes[path[j]].position);
        };
        // Rotation-minimizing basis: start from the chain frame's x axis and carry it along by
        // projecting onto each new ring plane.
        glm::dvec3 u = chain.frame[0];
        glm::dvec3 tangent = segment(0);
        const uint32_t first_vertex = uint32_t(mesh.vertices.size());
        for (size_t j = 0; j < rings; ++j) {
            if (j > 0) {
                glm::dvec3 t = j + 1 < rings ? segment(j - 1) + segment(j) : segment(j - 1);
                tangent = glm::length(t) > 1e-12 ? glm::normalize(t) : segment(j - 1);
                glm::dvec3 projected = u - glm::dot(u, tangent) * tangent;
                if (glm::length(projected) > 1e-9) u = glm::normalize(projected);
                else u = glm::normalize(glm::cross(tangent, glm::dvec3(chain.frame[2])));
            }
            glm::dvec3 v = glm::cross(tangent, u);
            const TreeNode& node = nodes[path[j]];
            const double radius = j == 0 ? nodes[path[1]].radius : node.radius;
            const int32_t fix_chain = (j == 0 && chain.parent >= 0) ? chain.parent : -1;
            for (uint32_t k = 0; k < sides; ++k) {
                double phi = 2.0 * std::numbers::pi * double(k) / double(sides);
                glm::dvec3 radial = std::cos(phi) * u + std::sin(phi) * v;
                mesh.vertices.push_back(rigid_vertex(tree, h, int32_t(c), fix_chain,
                                                     node.position + radius * radial, radial));
            }
        }
        mesh.ring_vertex_count += uint32_t(rings * sides);
        for (size_t j = 0; j + 1 < rings; ++j) {
            for (uint32_t k = 0; k < sides; ++k) {
                uint32_t a0 = first_vertex + uint32_t(j) * sides + k;
                uint32_t a1 = first_vertex + uint32_t(j) * sides + (k + 1) % sides;
                uint32_t b0 = a0 + sides, b1 = a1 + sides;
                mesh.indices.insert(mesh.indices.end(), {a0, a1, b1, a0, b1, b0});
            }
        }
        if (h.continuation[chain.members.back()] < 0) {
            const TreeNode& last = nodes[chain.members.back()];
            uint32_t tip = uint32_t(mesh.vertices.size());
            mesh.vertices.push_back(rigid_vertex(tree, h, int32_t(c), -1,
                                                 last.position + last.radius * tangent, tangent));
            ++mesh.tip_count;
            uint32_t ring = first_vertex + uint32_t(rings - 1) * sides;
            for (uint32_t k = 0; k < sides; ++k)
                mesh.indices.insert(mesh.indices.end(), {ring + k, ring + (k + 1) % sides, tip});
        }
    }
    for (const TreeLeaf& leaf : tree.leaves) {
        const glm::dvec3 centre = nodes[leaf.node].position + leaf.offset;
        const glm::dvec3 normal = glm::normalize(leaf.normal);
        const glm::dvec3 e_r = glm::normalize(glm::cross(leaf.up, normal));
        const glm::dvec3 e_u = glm::cross(normal, e_r);
        const glm::dvec3 half_r = 0.5 * leaf.size.x * e_r, half_u = 0.5 * leaf.size.y * e_u;
        const int32_t owner = h.node_owner[leaf.node];
        uint32_t base = uint32_t(mesh.vertices.size());
        for (glm::dvec3 corner : {centre - half_r - half_u, centre + half_r - half_u,
                                  centre + half_r + half_u, centre - half_r + half_u})
            mesh.vertices.push_back(rigid_vertex(tree, h, owner, -1, corner, normal));
        mesh.indices.insert(mesh.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
        ++mesh.leaf_count;
    }
    return mesh;
}

}  // namespace hmsm
