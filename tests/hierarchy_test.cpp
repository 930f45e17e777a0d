#include "test_trees.h"

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

using namespace hmsm;
using hmsm::test::make_tree;

namespace {

struct ExpectedChain {
    int32_t parent, depth, attach;
    std::vector<int32_t> members;
};

void expect_chains(const Hierarchy& h, const std::vector<ExpectedChain>& expected) {
    ASSERT_EQ(h.chains.size(), expected.size());
    for (size_t c = 0; c < expected.size(); ++c) {
        SCOPED_TRACE("chain " + std::to_string(c));
        EXPECT_EQ(h.chains[c].parent, expected[c].parent);
        EXPECT_EQ(h.chains[c].depth, expected[c].depth);
        EXPECT_EQ(h.chains[c].attach_node, expected[c].attach);
        EXPECT_EQ(h.chains[c].members, expected[c].members);
    }
}

// Root 0 with three children: 1 diagonal, 2 vertical, 3 low; 2 -> 4, 1 -> 5.
TreeModel three_children_at_root() {
    return make_tree({{-1, 0, 0, 0, 0.3},
                      {0, 1, 1, 0, 0.28},
                      {0, 0, 1, 0, 0.2},
                      {0, -1, 0.5, 0, 0.1},
                      {2, 0, 2, 0, 0.15},
                      {1, 2, 2, 0, 0.2}});
}

}  // namespace

TEST(Hierarchy, DirectionGroupingWithSeveralChildrenAtTheRoot) {
    auto h = build_hierarchy(three_children_at_root(), {});
    ASSERT_TRUE(h.ok()) << h.status().message();
    expect_chains(*h, {{-1, 0, 0, {2, 4}}, {0, 1, 0, {1, 5}}, {0, 1, 0, {3}}});
    EXPECT_EQ(h->max_depth, 1);
    EXPECT_EQ(h->chains_per_depth, (std::vector<int32_t>{1, 2}));
    EXPECT_EQ(h->node_owner, (std::vector<int32_t>{0, 1, 0, 2, 0, 1}));
}

TEST(Hierarchy, WidthGroupingFollowsTheClosestRadius) {
    ModelOptions options;
    options.grouping = Grouping::width;
    auto h = build_hierarchy(three_children_at_root(), options);
    ASSERT_TRUE(h.ok()) << h.status().message();
    // |0.28 - 0.3| is the smallest radius difference at the root.
    expect_chains(*h, {{-1, 0, 0, {1, 5}}, {0, 1, 0, {2, 4}}, {0, 1, 0, {3}}});
}

TEST(Hierarchy, TiesGoToTheLowestIndex) {
    auto tree = make_tree({{-1, 0, 0, 0, 0.3}, {0, 1, 1, 0, 0.2}, {0, -1, 1, 0, 0.2}});
    auto h = build_hierarchy(tree, {});
    ASSERT_TRUE(h.ok());
    expect_chains(*h, {{-1, 0, 0, {1}}, {0, 1, 0, {2}}});
    ModelOptions width;
    width.grouping = Grouping::width;
    auto hw = build_hierarchy(tree, width);
    ASSERT_TRUE(hw.ok());
    expect_chains(*hw, {{-1, 0, 0, {1}}, {0, 1, 0, {2}}});
}

TEST(Hierarchy, CutChainsContinueAsChildChains) {
    // A rod 0-1-...-6 with a side twig 7 at node 2 (the last node of the first cut chain).
    TreeModel tree = test::rod(6, 6.0, 0.2);
    tree.nodes.push_back({2, {0.5, 2.3, 0}, 0.05});
    ModelOptions options;
    options.max_chain_segments = 2;
    auto h = build_hierarchy(tree, options);
    ASSERT_TRUE(h.ok()) << h.status().message();
    // At node 2: first the side chain (7), then the continuation of the cut chain (3, 4).
    expect_chains(*h, {{-1, 0, 0, {1, 2}},
                       {0, 1, 2, {7}},
                       {0, 1, 2, {3, 4}},
                       {2, 2, 4, {5, 6}}});
    EXPECT_EQ(h->max_depth, 2);
    // Without cutting, the rod is one chain.
    auto whole = build_hierarchy(tree, {});
    ASSERT_TRUE(whole.ok());
    expect_chains(*whole, {{-1, 0, 0, {1, 2, 3, 4, 5, 6}}, {0, 1, 2, {7}}});
}

TEST(Hierarchy, UnsortedInputAndEveryNodeOwnedOnce) {
    TreeModel tree = test::small_tree();
    auto h = build_hierarchy(tree, {});
    ASSERT_TRUE(h.ok()) << h.status().message();
    EXPECT_EQ(h->chains[0].attach_node, 1);  // the root is node 1
    EXPECT_EQ(h->chains[0].members, (std::vector<int32_t>{2, 3, 0}));
    std::vector<int> owned(tree.nodes.size(), 0);
    owned[h->chains[0].attach_node]++;
    for (size_t c = 0; c < h->chains.size(); ++c) {
        for (int32_t m : h->chains[c].members) {
            owned[m]++;
            EXPECT_EQ(h->node_owner[m], int32_t(c));
        }
        if (c > 0) {  // the attach node belongs to the parent chain
            EXPECT_EQ(h->node_owner[h->chains[c].attach_node], h->chains[c].parent);
            EXPECT_EQ(h->chains[c].depth, h->chains[h->chains[c].parent].depth + 1);
            EXPECT_GE(h->chains[c].depth, h->chains[c - 1].depth);  // breadth-first
        }
    }
    for (int n : owned) EXPECT_EQ(n, 1);
    EXPECT_EQ(h->max_depth, 3);
}

TEST(Hierarchy, FramesAreOrthonormalRightHandedAndReproduceRestPositions) {
    TreeModel tree = test::small_tree();
    tree.nodes.push_back({1, {0.0, 0.0, 1.0}, 0.05});  // a chain along +z exercises ref = x
    auto h = build_hierarchy(tree, {});
    ASSERT_TRUE(h.ok());
    for (const Chain& chain : h->chains) {
        const glm::dmat3& b = chain.frame;
        glm::dmat3 identity = glm::transpose(b) * b;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) EXPECT_NEAR(identity[i][j], i == j ? 1.0 : 0.0, 1e-12);
        EXPECT_NEAR(glm::determinant(b), 1.0, 1e-12);
        glm::dvec3 y = glm::normalize(tree.nodes[chain.members[0]].position -
                                      tree.nodes[chain.attach_node].position);
        EXPECT_NEAR(glm::length(b[1] - y), 0.0, 1e-12);
        glm::dmat3 parent = chain.parent < 0 ? glm::dmat3(1.0) : h->chains[chain.parent].frame;
        glm::dmat3 q = parent * chain.rest_rotation;  // B_parent Q_c = B_c
        for (int i = 0; i < 3; ++i) EXPECT_NEAR(glm::length(q[i] - b[i]), 0.0, 1e-12);
    }
    for (size_t n = 0; n < tree.nodes.size(); ++n) {
        const Chain& chain = h->chains[h->node_owner[n]];
        glm::dvec3 p = tree.nodes[chain.attach_node].position + chain.frame * h->node_local[n];
        EXPECT_NEAR(glm::length(p - tree.nodes[n].position), 0.0, 1e-12) << "node " << n;
    }
}

TEST(Hierarchy, ConstantsFollowTheFormulas) {
    Parameters p;
    p.density = 2.0;
    p.stiffness = 1e5;
    p.damping_ratio = 0.2;
    p.wind_gain = 3.0;
    auto h = build_hierarchy(test::rod(4, 5.0, 0.2), {}, p);
    ASSERT_TRUE(h.ok());
    const Chain& c = h->chains[0];
    double r = 0.2, L = 5.0;
    EXPECT_NEAR(c.length, L, 1e-12);
    EXPECT_NEAR(c.radius, r, 1e-15);
    EXPECT_NEAR(c.inertia, 2.0 * r * r * L * L * L, 1e-12);
    EXPECT_NEAR(c.stiffness, 1e5 * std::pow(r, 4) / L, 1e-12);
    EXPECT_NEAR(c.damping, 2 * 0.2 * std::sqrt(c.stiffness * c.inertia), 1e-12);
    EXPECT_NEAR(c.wind_area, 3.0 * r * L * L, 1e-12);
    EXPECT_FALSE(c.capped);
    EXPECT_EQ(h->capped_chain_count, 0);
}

TEST(Hierarchy, FrequencyCapRaisesInertiaAndCountsIt) {
    // A short stiff chain: it would sway far faster than f_cap = 4 Hz.
    auto tree = make_tree({{-1, 0, 0, 0, 0.3}, {0, 0, 0.2, 0, 0.3}});
    Parameters p;
    auto h = build_hierarchy(tree, {}, p);
    ASSERT_TRUE(h.ok());
    const Chain& c = h->chains[0];
    EXPECT_TRUE(c.capped);
    EXPECT_EQ(h->capped_chain_count, 1);
    EXPECT_NEAR(std::sqrt(c.stiffness / c.inertia), 2.0 * std::numbers::pi * 4.0, 1e-9);
    // With a high cap the stability bound 1 / (4 pi dt max(1, zeta)) binds: omega dt = 0.5.
    p.max_frequency = 1000.0;
    auto fast = build_hierarchy(tree, {}, p);
    ASSERT_TRUE(fast.ok());
    const Chain& f = fast->chains[0];
    EXPECT_NEAR(std::sqrt(f.stiffness / f.inertia) * p.dt, 0.5, 1e-12);
}
