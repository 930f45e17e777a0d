// The coupled dynamics' links linearized about the rest pose (docs/model.md 3.13, "The links
// linearized"): every chain a rigid body of its own wood and leaves, turning about its joint's
// rest x and z axes with the joint's stiffness K and structural damping D, and the joint-space
// mass matrix M of the whole tree, which the dynamics keeps only on its diagonal. Products with M
// run in two sweeps over the chains (velocities down, momenta up), so no n x n matrix is formed;
// the lowest modes of K phi = omega^2 M phi come from subspace iteration.
#pragma once

#include <hmsm/hierarchy.h>
#include <hmsm/options.h>
#include <hmsm/tree.h>

#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include <array>
#include <cstdint>
#include <vector>

namespace hmsm::detail {

/// A rigid body's mass, first mass moment h = sum m x and rotational inertia
/// J = sum m (|x|^2 1 - x x^T), all about the model origin: its momentum at spatial velocity
/// (omega, v0) (v0 the velocity of the point at the origin) is linear m v0 + omega x h, angular
/// h x v0 + J omega.
struct BodyInertia {
    double mass = 0.0;
    glm::dvec3 moment{0.0};
    glm::dmat3 rotational{0.0};
    void add_point(const glm::dvec3& x, double m);
};

/// Chain c of the tree: joint 2c turns about axis[0] (the chain's rest x), joint 2c + 1 about
/// axis[1] (its rest z), both through `pivot`; model rest coordinates throughout.
struct LinkBody {
    int32_t parent = -1;
    glm::dvec3 pivot{0.0};
    std::array<glm::dvec3, 2> axis{};
    BodyInertia body;                  ///< own wood and leaves
    std::array<double, 2> stiffness{};  ///< K per joint (N m / rad)
    std::array<double, 2> damping{};    ///< structural D per joint (N m s / rad)
};

struct LinearizedLinks {
    std::vector<LinkBody> links;  ///< per chain, parents before children
    double total_mass = 0.0;
    size_t joints() const { return 2 * links.size(); }
};

/// The links of `h`, built from `tree` under Dynamics::coupled with its constants filled.
LinearizedLinks linearize_links(const TreeModel& tree, const Hierarchy& h, const Parameters& parameters);

/// out = M y, M the joint-space mass matrix (joints 2c + axis).
void link_mass_times(const LinearizedLinks& links, const std::vector<double>& y, std::vector<double>& out);

/// The generalized forces of a uniform acceleration field of 1 m/s^2 along `direction` acting on
/// every mass (a lateral load per unit mass).
std::vector<double> uniform_load(const LinearizedLinks& links, const glm::dvec3& direction);

struct LinkModes {
    std::vector<double> frequency_hz;  ///< lowest first
    /// Per mode, the share of the tree's mass it moves under a uniform acceleration along each
    /// of the two directions: (phi^T F)^2 / (phi^T M phi) / total mass.
    std::vector<std::array<double, 2>> mass_share;
    /// The whole tree's sway along each direction: Rayleigh's quotient with its static
    /// deflection under the uniform load, omega^2 = q^T F / q^T M q with q = K^-1 F (Hz).
    std::array<double, 2> sway_hz{};
    int iterations = 0;
    bool converged = false;
};

/// The `count` lowest modes (fewer when the tree has fewer joints) and the sway along
/// `directions` (unit vectors across the trunk).
LinkModes lowest_link_modes(const LinearizedLinks& links, int count, const std::array<glm::dvec3, 2>& directions);

}  // namespace hmsm::detail
