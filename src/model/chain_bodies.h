// What each chain of the coupled dynamics is made of (docs/model.md 3.13): its path straightened
// along its arc length with the radius at every node, its own wood as Gauss points of its
// frustums, and the leaf cards it owns as point masses. The per-chain constants
// (coupled_constants.cpp) and the linearized links (linearized_links.cpp) both start here.
#pragma once

#include <hmsm/hierarchy.h>
#include <hmsm/options.h>
#include <hmsm/tree.h>

#include <glm/vec3.hpp>

#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>

namespace hmsm::detail {

/// A chain straightened along its arc length: node j (0 the attach node) at local position p[j],
/// radius r[j], arc length s[j].
struct ChainPath {
    std::vector<glm::dvec3> p;
    std::vector<double> r, s;
};

/// A load in the chain's frame: mass and drag area at local position x, on path node path_index.
struct PointLoad {
    int32_t path_index;
    glm::dvec3 x;
    double mass, drag_area;
};

struct ChainBodies {
    std::vector<ChainPath> paths;                 ///< per chain
    std::vector<std::vector<PointLoad>> leaves;   ///< per chain: its leaf cards (leaf-on only)
    std::vector<int32_t> path_index;              ///< per node: its index along its owner's path
};

/// The paths and leaves of every chain of `h` (built from `tree`) under `parameters.foliage`.
/// The base takes the attach node's radius for the trunk and for a link after the first, the
/// first member's for a branch (its attach node's radius is the parent's), as the mesh's base
/// ring does.
ChainBodies chain_bodies(const TreeModel& tree, const Hierarchy& h, const Parameters& parameters);

/// Calls use(x, mass, drag_area) for the chain's own wood: each segment a frustum, 3-point
/// Gauss-Legendre along it (exact for the quartic integrands of mass and drag-area moments),
/// in order along the path.
template <class Use>
void for_each_wood_point(const ChainPath& path, const Material& material, double wood_drag_coefficient, Use&& use) {
    const double gauss_t[3] = {0.5 - std::sqrt(0.15), 0.5, 0.5 + std::sqrt(0.15)};
    const double gauss_w[3] = {5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0};
    for (size_t j = 1; j < path.p.size(); ++j) {
        const double len = path.s[j] - path.s[j - 1];
        for (int q = 0; q < 3; ++q) {
            const double r = path.r[j - 1] + (path.r[j] - path.r[j - 1]) * gauss_t[q];
            const glm::dvec3 x = path.p[j - 1] + (path.p[j] - path.p[j - 1]) * gauss_t[q];
            use(x, material.density * std::numbers::pi * r * r * len * gauss_w[q],
                wood_drag_coefficient * 2.0 * r * len * gauss_w[q]);
        }
    }
}

}  // namespace hmsm::detail
