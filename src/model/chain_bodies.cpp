// Each chain's path, radii and leaf cards (chain_bodies.h, docs/model.md 3.13).
#include "chain_bodies.h"

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

namespace hmsm::detail {

ChainBodies chain_bodies(const TreeModel& tree, const Hierarchy& h, const Parameters& parameters) {
    const auto& nodes = tree.nodes;
    const size_t chain_count = h.chains.size();
    ChainBodies b;
    b.path_index.assign(nodes.size(), 0);  // the trunk's root: 0
    b.paths.resize(chain_count);
    for (size_t c = 0; c < chain_count; ++c) {
        const Chain& chain = h.chains[c];
        ChainPath& path = b.paths[c];
        path.p.push_back(glm::dvec3(0.0));
        const bool continues = c == 0 || chain.dynamics.link_index > 0;
        path.r.push_back(continues ? nodes[chain.attach_node].radius : nodes[chain.members.front()].radius);
        path.s.push_back(0.0);
        for (size_t j = 0; j < chain.members.size(); ++j) {
            const int32_t m = chain.members[j];
            b.path_index[m] = int32_t(j + 1);
            path.s.push_back(path.s.back() + glm::length(h.node_local[m] - path.p.back()));
            path.p.push_back(h.node_local[m]);
            path.r.push_back(nodes[m].radius);
        }
    }
    // Leaves: mass and drag area from the card's area, at the node plus its offset.
    b.leaves.resize(chain_count);
    if (parameters.foliage.on) {
        for (const TreeLeaf& leaf : tree.leaves) {
            const int32_t owner = h.node_owner[leaf.node];
            const double area = leaf.size.x * leaf.size.y;
            const glm::dvec3 x = h.node_local[leaf.node] + glm::transpose(h.chains[owner].frame) * leaf.offset;
            b.leaves[owner].push_back({b.path_index[leaf.node], x, parameters.foliage.mass_per_area * area,
                                       parameters.foliage.drag_coefficient * area});
        }
    }
    return b;
}

}  // namespace hmsm::detail
