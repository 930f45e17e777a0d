// Leaf cards on the leaf-bearing twig nodes (docs/model.md 3.8 cards, 4 vertices each).
#pragma once

#include "params.h"
#include "skeleton.h"
#include "../random.h"

#include <hmsm/tree.h>

#include <glm/geometric.hpp>

#include <cmath>
#include <numbers>

namespace hmsm::detail::gen {

/// Spreads `count` leaves over the leaf-bearing nodes as evenly as possible (the first
/// count % nodes nodes, spaced along the list, get one more) and appends them to the tree.
/// Each card stands off its node along its own up axis, at `style.angle` to the twig, turned
/// around the twig by the golden angle, with its face towards the sky plus some scatter.
inline void add_leaves(Skeleton& skeleton, uint64_t count, const LeafStyle& style, Random& rng) {
    const size_t sites = skeleton.leaf_nodes.size();
    if (sites == 0 || count == 0) return;
    const uint64_t base = count / sites, extra = count % sites;
    auto& leaves = skeleton.tree.leaves;
    leaves.reserve(leaves.size() + count);
    double azimuth = rng.uniform(0.0, 2.0 * std::numbers::pi);
    for (size_t i = 0; i < sites; ++i) {
        // Node i gets an extra leaf when the evenly spaced remainder steps past it.
        const uint64_t here = base + ((uint64_t(i + 1) * extra) / sites - (uint64_t(i) * extra) / sites);
        const glm::dvec3 d = skeleton.leaf_dirs[i];
        const glm::dvec3 side = perpendicular(d, glm::dvec3(0, 1, 0));
        const glm::dvec3 binormal = glm::cross(d, side);
        for (uint64_t k = 0; k < here; ++k) {
            azimuth += kGoldenAngle;
            const double angle = style.angle + 0.15 * clamped_normal(rng, 2.0);
            const glm::dvec3 radial = std::cos(azimuth) * side + std::sin(azimuth) * binormal;
            const glm::dvec3 up = glm::normalize(std::cos(angle) * d + std::sin(angle) * radial);
            // Face the sky, scattered, then made exactly perpendicular to the card's up axis.
            glm::dvec3 sky = glm::dvec3(0.35 * clamped_normal(rng), 1.0, 0.35 * clamped_normal(rng));
            const glm::dvec3 normal = perpendicular(up, sky);
            const double scale = std::max(0.5, 1.0 + style.size_var * clamped_normal(rng, 2.0));
            TreeLeaf leaf;
            leaf.node = skeleton.leaf_nodes[i];
            leaf.size = glm::dvec2(style.width * scale, style.height * scale);
            leaf.offset = (style.petiole + 0.5 * leaf.size.y) * up;
            leaf.normal = normal;
            leaf.up = up;
            leaves.push_back(leaf);
        }
    }
}

}  // namespace hmsm::detail::gen
