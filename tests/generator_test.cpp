// The paper presets (docs/model.md 6): Table 1 vertex counts, five branching orders, leaves,
// real-world size and natural trunk sway, determinism, and the error for an unknown name.
#include <hmsm/generator.h>
#include <hmsm/hierarchy.h>
#include <hmsm/mesh.h>

#include "model/generator/presets.h"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

using namespace hmsm;

namespace {

struct PresetCase {
    const char* name;
    uint64_t table1_vertices;  ///< the paper's Table 1
    bool forked;               ///< Fig. 9: a forked crown (else a multi-branch crown)
};

const PresetCase kPresets[] = {
    {"paper-1", 78563, false}, {"paper-2", 24902, true}, {"paper-3", 37823, false},
    {"paper-4", 26792, true},  {"paper-5", 15731, false},
};

/// Trunk chain path: the root, then its members.
std::vector<int32_t> trunk_path(const Hierarchy& h) {
    std::vector<int32_t> path{h.chains[0].attach_node};
    path.insert(path.end(), h.chains[0].members.begin(), h.chains[0].members.end());
    return path;
}

/// Trunk radius at 1.3 m above the root (breast height), interpolated along the trunk chain.
double radius_at_breast_height(const TreeModel& tree, const Hierarchy& h) {
    const auto path = trunk_path(h);
    const double y0 = tree.nodes[size_t(path[0])].position.y + 1.3;
    for (size_t j = 0; j + 1 < path.size(); ++j) {
        const TreeNode& a = tree.nodes[size_t(path[j])];
        const TreeNode& b = tree.nodes[size_t(path[j + 1])];
        if (a.position.y <= y0 && b.position.y > y0) {
            const double f = (y0 - a.position.y) / (b.position.y - a.position.y);
            return a.radius + f * (b.radius - a.radius);
        }
    }
    return 0.0;
}

class PresetTest : public ::testing::TestWithParam<PresetCase> {
protected:
    void SetUp() override {
        auto generated = generate_preset(GetParam().name);
        ASSERT_TRUE(generated.ok()) << generated.status().message();
        tree_ = std::move(generated).value();
        auto hierarchy = build_hierarchy(tree_, ModelOptions{});
        ASSERT_TRUE(hierarchy.ok()) << hierarchy.status().message();
        h_ = std::move(hierarchy).value();
    }
    TreeModel tree_;
    Hierarchy h_;
};

}  // namespace

TEST(Generator, PresetNames) {
    const auto& names = preset_names();
    ASSERT_EQ(names.size(), 5u);
    for (size_t i = 0; i < names.size(); ++i)
        EXPECT_EQ(names[i], "paper-" + std::to_string(i + 1));
}

TEST(Generator, UnknownPresetIsAnInvalidArgumentThatNamesIt) {
    auto result = generate_preset("paper-9");
    ASSERT_FALSE(result.ok());
    EXPECT_EQ(result.status().code(), ErrorCode::invalid_argument);
    EXPECT_NE(result.status().message().find("'paper-9'"), std::string::npos)
        << result.status().message();
    EXPECT_NE(result.status().message().find("paper-1"), std::string::npos)
        << result.status().message();
    EXPECT_FALSE(generate_preset("").ok());
}

TEST_P(PresetTest, IsAValidTree) {
    Status status = validate_tree(tree_);
    EXPECT_TRUE(status.ok()) << status.message();
}

TEST_P(PresetTest, VertexCountMatchesTable1WithinOnePercent) {
    const double count = double(mesh_vertex_count(tree_, h_, ModelOptions{}));
    const double expected = double(GetParam().table1_vertices);
    EXPECT_LE(std::abs(count - expected), 0.01 * expected) << "vertex count " << count;
    EXPECT_EQ(build_mesh(tree_, h_, ModelOptions{}).vertices.size(), uint64_t(count));
}

TEST_P(PresetTest, HasFiveBranchingOrders) {
    EXPECT_EQ(h_.max_depth, 4);
    ASSERT_EQ(h_.chains_per_depth.size(), 5u);
    for (int32_t count : h_.chains_per_depth) EXPECT_GT(count, 0);
}

TEST_P(PresetTest, RealWorldSize) {
    const double height = tree_height(tree_);
    EXPECT_GE(height, 8.0);
    EXPECT_LE(height, 20.0);
    const double base_radius = tree_.nodes[size_t(h_.chains[0].attach_node)].radius;
    EXPECT_GE(base_radius, 0.15);
    EXPECT_LE(base_radius, 0.5);
    // Trunk diameter at breast height over height squared, as measured on real trees.
    const double dbh = 2.0 * radius_at_breast_height(tree_, h_);
    EXPECT_GE(dbh / (height * height), 0.0006) << "DBH " << dbh << " H " << height;
    EXPECT_LE(dbh / (height * height), 0.0035) << "DBH " << dbh << " H " << height;
}

TEST_P(PresetTest, TrunkSwaysAtANaturalFrequency) {
    const Chain& trunk = h_.chains[0];
    EXPECT_FALSE(trunk.capped);
    const double frequency = std::sqrt(trunk.stiffness / trunk.inertia) / (2.0 * std::numbers::pi);
    EXPECT_GE(frequency, 0.2);
    EXPECT_LE(frequency, 0.8);
}

TEST_P(PresetTest, SegmentsAndRadiiArePlausible) {
    for (size_t i = 0; i < tree_.nodes.size(); ++i) {
        const TreeNode& node = tree_.nodes[i];
        if (node.parent < 0) continue;
        const double length = glm::length(node.position - tree_.nodes[size_t(node.parent)].position);
        EXPECT_GE(length, 0.1 - 1e-9) << "node " << i;
        EXPECT_LE(length, 1.0 + 1e-9) << "node " << i;
    }
    for (size_t c = 0; c < h_.chains.size(); ++c) {
        const Chain& chain = h_.chains[c];
        // A branch starts thinner than its parent where it attaches, and tapers towards its tip.
        double previous = tree_.nodes[size_t(chain.attach_node)].radius;
        for (int32_t m : chain.members) {
            const double radius = tree_.nodes[size_t(m)].radius;
            if (c > 0 && m == chain.members.front()) EXPECT_LT(radius, previous) << "chain " << c;
            else EXPECT_LE(radius, previous + 1e-12) << "chain " << c << " node " << m;
            previous = radius;
        }
    }
}

TEST_P(PresetTest, LeavesAreCardsOnTwigs) {
    ASSERT_GT(tree_.leaves.size(), 0u);
    size_t on_twigs = 0;
    for (size_t j = 0; j < tree_.leaves.size(); ++j) {
        const TreeLeaf& leaf = tree_.leaves[j];
        ASSERT_GE(leaf.node, 0);
        ASSERT_LT(size_t(leaf.node), tree_.nodes.size());
        if (h_.chains[size_t(h_.node_owner[size_t(leaf.node)])].depth >= 3) ++on_twigs;
        EXPECT_GE(std::min(leaf.size.x, leaf.size.y), 0.02) << "leaf " << j;
        EXPECT_LE(std::max(leaf.size.x, leaf.size.y), 0.2) << "leaf " << j;
        const double cosine = glm::dot(glm::normalize(leaf.normal), glm::normalize(leaf.up));
        EXPECT_LT(std::abs(cosine), 0.9) << "leaf " << j;
        EXPECT_LT(glm::length(leaf.offset), 0.3) << "leaf " << j;
    }
    EXPECT_EQ(on_twigs, tree_.leaves.size());
    // A plausible number: a few cards per leaf-bearing node, not dozens.
    std::vector<int32_t> nodes;
    for (const TreeLeaf& leaf : tree_.leaves) nodes.push_back(leaf.node);
    std::sort(nodes.begin(), nodes.end());
    nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
    EXPECT_LE(double(tree_.leaves.size()) / double(nodes.size()), 10.0);
}

// Fig. 9: the forked presets split the trunk into co-dominant leaders (a second stem from the
// lower half of the tree, nearly as thick as the trunk there); the multi-branch ones do not.
TEST_P(PresetTest, CrownShape) {
    const double base = tree_.nodes[size_t(h_.chains[0].attach_node)].position.y;
    const double height = tree_height(tree_);
    int leaders = 0;
    for (const Chain& chain : h_.chains) {
        if (chain.depth != 1) continue;
        const TreeNode& attach = tree_.nodes[size_t(chain.attach_node)];
        if (attach.position.y - base < 0.5 * height && chain.radius >= 0.55 * attach.radius) ++leaders;
    }
    if (GetParam().forked) EXPECT_GE(leaders, 1);
    else EXPECT_EQ(leaders, 0);
}

TEST_P(PresetTest, Deterministic) {
    auto again = generate_preset(GetParam().name);
    ASSERT_TRUE(again.ok());
    EXPECT_EQ(tree_to_json(*again), tree_to_json(tree_));
    // Seed 0 is the preset's own seed.
    for (const auto& spec : detail::gen::presets()) {
        if (spec.name != GetParam().name) continue;
        auto own = generate_preset(GetParam().name, spec.seed);
        ASSERT_TRUE(own.ok());
        EXPECT_EQ(tree_to_json(*own), tree_to_json(tree_));
    }
}

TEST_P(PresetTest, OtherSeedsGiveOtherTreesOfSimilarSize) {
    for (uint64_t seed : {7ull, 12345ull}) {
        auto other = generate_preset(GetParam().name, seed);
        ASSERT_TRUE(other.ok()) << other.status().message();
        EXPECT_NE(tree_to_json(*other), tree_to_json(tree_));
        auto h = build_hierarchy(*other, ModelOptions{});
        ASSERT_TRUE(h.ok());
        EXPECT_EQ(h->max_depth, 4);
        const double count = double(mesh_vertex_count(*other, *h, ModelOptions{}));
        const double expected = double(GetParam().table1_vertices);
        EXPECT_LE(std::abs(count - expected), 0.03 * expected) << "seed " << seed;
        const double height = tree_height(*other);
        EXPECT_GE(height, 8.0);
        EXPECT_LE(height, 20.0);
    }
}

INSTANTIATE_TEST_SUITE_P(Presets, PresetTest, ::testing::ValuesIn(kPresets),
                         [](const auto& info) {
                             std::string name = info.param.name;
                             std::replace(name.begin(), name.end(), '-', '_');
                             return name;
                         });
