// The loads a coupled chain's cantilever carries (docs/model.md 3.13): leaves and side chains are
// rigid bodies whose centroid may lie off their node along the chain. A heavy point on a nearly
// massless cantilever, off the tip along the axis or on a side chain, has the exact frequency
// sqrt(1 / (m c)) with c the compliance of its own displacement (a point mass: one mode, which
// Rayleigh's quotient with the static shape gives exactly).
#include "test_trees.h"

#include <hmsm/hierarchy.h>

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

using namespace hmsm;

namespace {

constexpr double kLength = 2.0, kRadius = 0.05, kMass = 100.0;

/// Wood as light as the valid range allows and a 1 m x 1 m leaf card of kMass: the card is the
/// load, the wood a fraction of a percent of it.
Parameters heavy_leaf_parameters() {
    Parameters parameters;
    parameters.material.density = 10.0;
    parameters.foliage.on = true;
    parameters.foliage.mass_per_area = kMass;
    return parameters;
}

/// First frequency (Hz) of a point mass kMass whose lateral displacement under a unit force is
/// `compliance` (m/N).
double point_mass_frequency(double compliance) {
    return std::sqrt(1.0 / (kMass * compliance)) / (2.0 * std::numbers::pi);
}

double bending_stiffness(const Parameters& parameters) {
    return parameters.material.modulus * std::numbers::pi * std::pow(kRadius, 4) / 4.0;
}

}  // namespace

// A mass at axial distance a beyond the tip of a cantilever of length L moves, under a unit
// force, by the tip deflection plus a times the tip slope: (L^3/3 + a L^2 + a^2 L) / (E J).
// Lumped at the tip it would give L^3 / (3 E J): 7 times stiffer for a = L.
TEST(CoupledLoads, LeafBeyondTheTipLoadsTheCantileverThroughItsLever) {
    const Parameters parameters = heavy_leaf_parameters();
    TreeModel tree = test::rod(1, kLength, kRadius);
    const double a = kLength;
    tree.leaves.push_back({1, {0, a, 0}, {0, 0, 1}, {0, 1, 0}, {1.0, 1.0}});
    ModelOptions options;
    options.dynamics = Dynamics::coupled;
    auto h = build_hierarchy(tree, options, parameters);
    ASSERT_TRUE(h.ok()) << h.status().message();
    ASSERT_EQ(h->chains.size(), 1u);
    const double L = kLength, EJ = bending_stiffness(parameters);
    const double expected = point_mass_frequency((L * L * L / 3.0 + a * L * L + a * a * L) / EJ);
    for (int axis = 0; axis < 2; ++axis)
        EXPECT_NEAR(h->chains[0].dynamics.frequency[axis], expected, 0.01 * expected) << "axis " << axis;
}

// A side chain leaning 30 degrees off the trunk's top carries the mass at its end, at axial
// distance a = c cos 30 beyond the trunk's tip and c sin 30 to the side (along x). Swaying along
// z (about the trunk's x axis) the mass moves by w + a theta only: the point-mass frequency of
// compliance (L^3/3 + a L^2 + a^2 L) / (E J), with the side chain rigid as the parent's
// cantilever takes its children. A short thin stub continues the trunk, so the side chain is
// a chain of its own.
TEST(CoupledLoads, SideChainLoadsItsParentThroughItsCentroid) {
    const Parameters parameters = heavy_leaf_parameters();
    const double L = kLength, c = 1.0, lean = std::numbers::pi / 6.0;
    TreeModel tree;
    tree.nodes.push_back({-1, {0, 0, 0}, kRadius});
    tree.nodes.push_back({0, {0, L, 0}, kRadius});
    tree.nodes.push_back({1, {0, L + 0.01, 0}, 0.005});
    tree.nodes.push_back({1, {c * std::sin(lean), L + c * std::cos(lean), 0}, 0.02});
    tree.leaves.push_back({3, {0, 0, 0}, {0, 0, 1}, {0, 1, 0}, {1.0, 1.0}});
    ModelOptions options;
    options.dynamics = Dynamics::coupled;
    auto h = build_hierarchy(tree, options, parameters);
    ASSERT_TRUE(h.ok()) << h.status().message();
    const Chain& trunk = h->chains[0];
    ASSERT_EQ(trunk.members.size(), 1u);
    ASSERT_NE(h->node_owner[3], 0) << "the leaning node is a side chain";
    ASSERT_NE(h->node_owner[3], h->node_owner[2]) << "the stub continues the trunk";
    const double a = c * std::cos(lean), EJ = bending_stiffness(parameters);
    const double expected = point_mass_frequency((L * L * L / 3.0 + a * L * L + a * a * L) / EJ);
    EXPECT_NEAR(trunk.dynamics.frequency[0], expected, 0.01 * expected);
    // The subtree's centroid in the trunk's rigid inertia: the mass at distance^2
    // (L + a)^2 from the x axis through the joint.
    EXPECT_NEAR(trunk.dynamics.rigid_inertia[0], kMass * (L + a) * (L + a), 0.01 * kMass * (L + a) * (L + a));
}
