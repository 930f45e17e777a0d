// The coupled links linearized about the rest pose (docs/model.md 3.13, "The links linearized"):
// the joint-space mass matrix of two point masses on springs against its closed form, their
// modes and sway; a rod split into links against the cantilever's first two modes; a preset's
// trunk entry against the inertia the dynamics lumps.
#include "test_trees.h"

#include "model/coupled_constants.h"
#include "model/linearized_links.h"

#include <hmsm/generator.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>

using namespace hmsm;
using detail::LinearizedLinks;

namespace {

const std::array<glm::dvec3, 2> kAcross{glm::dvec3(1, 0, 0), glm::dvec3(0, 0, 1)};

/// M e_j, column j of the mass matrix.
std::vector<double> mass_column(const LinearizedLinks& links, size_t j) {
    std::vector<double> e(links.joints(), 0.0), out;
    e[j] = 1.0;
    detail::link_mass_times(links, e, out);
    return out;
}

}  // namespace

// Point mass m1 at height l1 on a spring joint at the ground, m2 at l2 above it on a second joint:
// across either axis M = [[m1 l1^2 + m2 (l1 + l2)^2, m2 l2 (l1 + l2)], [m2 l2 (l1 + l2), m2 l2^2]],
// and the frequencies solve det(K - omega^2 M) = 0.
TEST(LinearizedLinks, TwoPointMassesOnSpringsHaveTheClosedFormModes) {
    const double m1 = 3.0, m2 = 1.5, l1 = 2.0, l2 = 1.2, k1 = 400.0, k2 = 90.0;
    LinearizedLinks links;
    links.links.resize(2);
    for (int c = 0; c < 2; ++c) {
        auto& link = links.links[size_t(c)];
        link.parent = c - 1;
        link.pivot = glm::dvec3(0, c == 0 ? 0.0 : l1, 0);
        link.axis = {glm::dvec3(1, 0, 0), glm::dvec3(0, 0, 1)};
        link.body.add_point(glm::dvec3(0, c == 0 ? l1 : l1 + l2, 0), c == 0 ? m1 : m2);
        link.stiffness = {c == 0 ? k1 : k2, c == 0 ? k1 : k2};
    }
    links.total_mass = m1 + m2;
    const double m11 = m1 * l1 * l1 + m2 * (l1 + l2) * (l1 + l2), m12 = m2 * l2 * (l1 + l2), m22 = m2 * l2 * l2;
    for (size_t axis = 0; axis < 2; ++axis) {
        const auto c0 = mass_column(links, axis), c1 = mass_column(links, 2 + axis);
        EXPECT_NEAR(c0[axis], m11, 1e-12 * m11);
        EXPECT_NEAR(c0[2 + axis], m12, 1e-12 * m11);
        EXPECT_NEAR(c1[axis], m12, 1e-12 * m11);
        EXPECT_NEAR(c1[2 + axis], m22, 1e-12 * m11);
        EXPECT_NEAR(c0[1 - axis], 0.0, 1e-12 * m11);  // the two axes do not couple here
        EXPECT_NEAR(c0[3 - axis], 0.0, 1e-12 * m11);
    }
    // det(K - L M) = 0: a L^2 - b L + c = 0.
    const double a = m11 * m22 - m12 * m12, b = k1 * m22 + k2 * m11, c = k1 * k2;
    const double low = (b - std::sqrt(b * b - 4 * a * c)) / (2 * a), high = (b + std::sqrt(b * b - 4 * a * c)) / (2 * a);
    const double two_pi = 2 * std::numbers::pi;
    const auto modes = detail::lowest_link_modes(links, 4, kAcross);
    ASSERT_TRUE(modes.converged);
    ASSERT_EQ(modes.frequency_hz.size(), 4u);
    for (int k = 0; k < 2; ++k) EXPECT_NEAR(modes.frequency_hz[size_t(k)], std::sqrt(low) / two_pi, 1e-9);
    for (int k = 2; k < 4; ++k) EXPECT_NEAR(modes.frequency_hz[size_t(k)], std::sqrt(high) / two_pi, 1e-9);
    // The sway along x (the z joints): F = -(m1 l1 + m2 (l1 + l2), m2 l2), q = K^-1 F.
    const double f1 = m1 * l1 + m2 * (l1 + l2), f2 = m2 * l2, q1 = f1 / k1, q2 = f2 / k2;
    const double sway = std::sqrt((q1 * f1 + q2 * f2) / (q1 * (m11 * q1 + m12 * q2) + q2 * (m12 * q1 + m22 * q2)));
    EXPECT_NEAR(modes.sway_hz[0], sway / two_pi, 1e-9);
    EXPECT_NEAR(modes.sway_hz[1], sway / two_pi, 1e-9);
    // Over all modes the shares along x add up to F^T M^-1 F / (m1 + m2).
    const double moved = (m22 * f1 * f1 - 2 * m12 * f1 * f2 + m11 * f2 * f2) / a;
    double shares[2] = {0, 0};
    for (const auto& s : modes.mass_share)
        for (int d = 0; d < 2; ++d) shares[d] += s[size_t(d)];
    for (int d = 0; d < 2; ++d) EXPECT_NEAR(shares[d], moved / (m1 + m2), 1e-9);
    EXPECT_NEAR(moved, m1 + m2, 1e-12);  // two joints move both masses freely across
}

// A uniform rod split into six links with the mass matrix of its rigid links: the lowest pair of
// modes (one per axis) near the cantilever's first frequency, the next pair near its second
// (beta_2^2 / beta_1^2 = 6.267 times higher; six links resolve it coarsely), the sway by the
// static deflection just above the first; each link's diagonal entry is the rigid rod beyond
// its joint, the inertia the dynamics lumps.
TEST(LinearizedLinks, SplitRodSwaysAtTheCantileverModes) {
    ModelOptions options;
    options.dynamics = Dynamics::coupled;
    Parameters parameters;
    const double length = 10.0, radius = 0.1;
    const TreeModel rod = test::rod(12, length, radius);
    auto h = build_hierarchy(rod, options, parameters);
    ASSERT_TRUE(h.ok()) << h.status().message();
    const LinearizedLinks links = detail::linearize_links(rod, *h, parameters);
    ASSERT_EQ(links.links.size(), size_t(detail::kTrunkLinks));
    for (size_t c = 0; c < links.links.size(); ++c)
        for (size_t a = 0; a < 2; ++a) {
            const double rigid = h->chains[c].dynamics.rigid_inertia[a];
            EXPECT_NEAR(mass_column(links, 2 * c + a)[2 * c + a], rigid, 1e-9 * rigid) << "link " << c;
        }
    const double f1 = detail::uniform_cantilever_frequency(length, radius, parameters.material);
    const auto modes = detail::lowest_link_modes(links, 4, kAcross);
    ASSERT_TRUE(modes.converged);
    std::printf("split rod: modes %.4f %.4f %.4f %.4f Hz (cantilever %.4f, %.4f), sway %.4f Hz, share %.3f\n",
                modes.frequency_hz[0], modes.frequency_hz[1], modes.frequency_hz[2], modes.frequency_hz[3], f1,
                f1 * std::pow(4.69409113 / 1.87510407, 2), modes.sway_hz[0],
                modes.mass_share[0][0] + modes.mass_share[1][0]);
    for (int k = 0; k < 2; ++k) EXPECT_NEAR(modes.frequency_hz[size_t(k)], f1, 0.03 * f1) << "mode " << k;
    const double f2 = f1 * std::pow(4.69409113 / 1.87510407, 2);
    for (int k = 2; k < 4; ++k) EXPECT_NEAR(modes.frequency_hz[size_t(k)], f2, 0.1 * f2) << "mode " << k;
    for (int d = 0; d < 2; ++d) {
        EXPECT_GT(modes.sway_hz[size_t(d)], modes.frequency_hz[0]);
        EXPECT_LT(modes.sway_hz[size_t(d)], 1.01 * modes.frequency_hz[0]);
    }
    // The first mode moves most of the rod's mass across; a cantilever's first mode: 61 %.
    EXPECT_NEAR(modes.mass_share[0][0] + modes.mass_share[1][0], 0.613, 0.05);
}

// On a preset the trunk's entry of the mass matrix is the rigid inertia its constants lump
// (everything beyond the joint about it), but for each child's inertia about its own axis and
// its products of inertia, which the lumping leaves out.
TEST(LinearizedLinks, TrunkEntryMatchesTheLumpedInertia) {
    ModelOptions options;
    options.dynamics = Dynamics::coupled;
    Parameters parameters;
    auto tree = generate_preset("paper-1");
    ASSERT_TRUE(tree.ok());
    auto h = build_hierarchy(*tree, options, parameters);
    ASSERT_TRUE(h.ok()) << h.status().message();
    const LinearizedLinks links = detail::linearize_links(*tree, *h, parameters);
    for (size_t a = 0; a < 2; ++a) {
        const double rigid = h->chains[0].dynamics.rigid_inertia[a];
        EXPECT_NEAR(mass_column(links, a)[a], rigid, 0.01 * rigid);
    }
    double mass = 0;
    for (const auto& link : links.links) mass += link.body.mass;
    EXPECT_NEAR(mass, h->chains[0].dynamics.subtree_mass, 1e-9 * mass);
    const auto modes = detail::lowest_link_modes(links, 4, kAcross);
    EXPECT_TRUE(modes.converged);
    ASSERT_EQ(modes.frequency_hz.size(), 4u);
    // Flexible limbs: the tree sways below its trunk chain's rigid-crown f0.
    for (int d = 0; d < 2; ++d) EXPECT_LT(modes.sway_hz[size_t(d)], h->chains[0].dynamics.frequency[d]);
}
