// Levels of detail (docs/model.md 3.12, include/hmsm/levels.h): budgets give the joint counts
// asked for, a level is a consistent model whose kept chains move exactly as the full model's
// (checked with an independent double-precision stepper of passes 1-3 against cpu64), the
// trunk's first frequency is kept, the skin of a level is the full mesh at rest and follows the
// full model's kept chains, and bad budgets are refused.
#include "test_trees.h"

#include <hmsm/levels.h>
#include <hmsm/skin.h>

#include <gtest/gtest.h>

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <utility>

using namespace hmsm;

namespace {

struct Model {
    TreeModel tree;
    Hierarchy full;
};

Model preset_model(const char* name) {
    auto tree = generate_preset(name);
    EXPECT_TRUE(tree.ok()) << tree.status().message();
    auto full = build_hierarchy(*tree, {}, {});
    EXPECT_TRUE(full.ok()) << full.status().message();
    return {*tree, *full};
}

/// Chain c or one of its ancestors.
bool is_self_or_ancestor(const Hierarchy& h, int32_t ancestor, int32_t c) {
    for (; c >= 0; c = h.chains[size_t(c)].parent)
        if (c == ancestor) return true;
    return false;
}

/// Checks that `level` is a model of `tree` on its own: chains breadth-first with parents
/// before children, every node carried by a chain whose rest frame and attach node put it back
/// at its rest position, and the maps between full and level chains consistent.
void expect_consistent(const TreeModel& tree, const Hierarchy& full, const DetailLevel& level) {
    const Hierarchy& h = level.hierarchy;
    ASSERT_EQ(level.source_chain.size(), h.chains.size());
    ASSERT_EQ(level.chain_of.size(), full.chains.size());
    EXPECT_EQ(h.chains[0].parent, -1);
    for (size_t c = 1; c < h.chains.size(); ++c) {
        EXPECT_GE(h.chains[c].parent, 0);
        EXPECT_LT(h.chains[c].parent, int32_t(c));
        EXPECT_GE(h.chains[c].depth, h.chains[c - 1].depth);
        EXPECT_EQ(h.chains[c].depth, h.chains[size_t(h.chains[c].parent)].depth + 1);
    }
    for (size_t c = 0; c < h.chains.size(); ++c) {
        const int32_t source = level.source_chain[c];
        EXPECT_EQ(level.chain_of[size_t(source)], int32_t(c));
        EXPECT_EQ(h.chains[c].inertia, full.chains[size_t(source)].inertia);
        EXPECT_EQ(h.chains[c].stiffness, full.chains[size_t(source)].stiffness);
    }
    for (size_t c = 0; c < full.chains.size(); ++c)
        EXPECT_TRUE(is_self_or_ancestor(full, level.source_chain[size_t(level.chain_of[c])], int32_t(c)))
            << "full chain " << c << " is carried by a chain that is not its own or an ancestor";
    int32_t counted = 0;
    for (int32_t n : h.chains_per_depth) counted += n;
    EXPECT_EQ(counted, int32_t(h.chains.size()));
    const glm::dvec3 root(tree.nodes[size_t(h.chains[0].attach_node)].position);
    const double height = tree_height(tree);
    for (size_t n = 0; n < tree.nodes.size(); ++n) {
        const Chain& carrier = h.chains[size_t(h.node_owner[n])];
        const glm::dvec3 attach = glm::dvec3(tree.nodes[size_t(carrier.attach_node)].position) - root;
        const glm::dvec3 rest = attach + glm::dmat3(carrier.frame) * glm::dvec3(h.node_local[n]);
        ASSERT_LT(glm::length(rest - (glm::dvec3(tree.nodes[n].position) - root)), 1e-9 * height) << "node " << n;
    }
}

TEST(Levels, DefaultBudgetsGiveTheirJointCountsNested) {
    for (const char* name : {"paper-5", "paper-1"}) {
        SCOPED_TRACE(name);
        const Model m = preset_model(name);
        auto levels = build_levels(m.tree, m.full, {});
        ASSERT_TRUE(levels.ok()) << levels.status().message();
        ASSERT_EQ(levels->size(), 4u);
        const int32_t expected[] = {256, 64, 16, 1};
        for (size_t i = 0; i < 4; ++i) {
            const DetailLevel& level = (*levels)[i];
            EXPECT_EQ(level.budget, expected[i]);
            EXPECT_EQ(level.joint_count(), expected[i]);
            expect_consistent(m.tree, m.full, level);
            if (i == 0) continue;
            const auto& finer = (*levels)[i - 1].source_chain;
            for (int32_t c : level.source_chain)  // nested: a coarser level keeps a subset
                EXPECT_TRUE(std::binary_search(finer.begin(), finer.end(), c)) << "chain " << c;
            EXPECT_GE(level.geometric_error_m, (*levels)[i - 1].geometric_error_m * 0.999);
        }
        EXPECT_GT(levels->back().geometric_error_m, 0.0);
        EXPECT_EQ(levels->back().hierarchy.max_depth, 0);
        for (int32_t owner : levels->back().hierarchy.node_owner) EXPECT_EQ(owner, 0);
    }
}

/// Every budget from the chain count down to 1 on small trees, with chains cut by
/// max_chain_segments too: the joint count asked for and a consistent model each time.
TEST(Levels, EveryBudgetOfSmallTreesGivesAConsistentModel) {
    ModelOptions cut;
    cut.max_chain_segments = 2;
    for (const auto& [tree, options] : {std::pair{test::small_tree(), ModelOptions{}}, std::pair{test::small_tree(), cut},
                                        std::pair{test::deep_tree(6), cut}}) {
        auto full = build_hierarchy(tree, options, {});
        ASSERT_TRUE(full.ok()) << full.status().message();
        const int32_t chains = int32_t(full->chains.size());
        ASSERT_GT(chains, 3);
        for (int32_t budget = chains; budget >= 1; --budget) {
            SCOPED_TRACE("budget " + std::to_string(budget) + " of " + std::to_string(chains));
            auto level = build_level(tree, *full, {}, budget);
            ASSERT_TRUE(level.ok()) << level.status().message();
            EXPECT_EQ(level->joint_count(), budget);
            expect_consistent(tree, *full, *level);
        }
    }
}

/// The trunk's first frequency (docs/model.md 3.12: sqrt(K_0 / I_0) / 2π, the trunk being its
/// own oscillator in 3.7) of every level is the full model's, within 5 %; checked as a physics
/// result by integrating each trunk's free sway with pass 2's integrator and timing its zero
/// crossings.
double measured_trunk_frequency(const Chain& trunk, double dt) {
    double s = 0.1, v = 0.0;  // released from a bend, no force
    std::vector<double> crossings;
    for (int step = 1; step < 200000 && crossings.size() < 9; ++step) {
        const double previous = s;
        v += dt / trunk.inertia * (-trunk.stiffness * s - trunk.damping * v);
        s += dt * v;
        if ((previous > 0.0) != (s > 0.0)) crossings.push_back((step - 1 + previous / (previous - s)) * dt);
    }
    EXPECT_GE(crossings.size(), 9u);
    return 4.0 / (crossings.back() - crossings.front());  // 8 half periods
}

TEST(Levels, TrunkFrequencyWithinFivePercentOfTheFullModel) {
    for (const char* name : {"paper-5", "paper-1"}) {
        SCOPED_TRACE(name);
        const Model m = preset_model(name);
        auto levels = build_levels(m.tree, m.full, {}, {256, 64, 16, 4, 1});
        ASSERT_TRUE(levels.ok()) << levels.status().message();
        const double dt = Parameters{}.dt;
        const double full = measured_trunk_frequency(m.full.chains[0], dt);
        // Damped (ζ = 0.1) and discretised, the sway stays within 5 % of the analytic f0.
        EXPECT_NEAR(full, (*levels)[0].full_trunk_frequency_hz, 0.05 * full);
        for (const DetailLevel& level : *levels) {
            const double f = measured_trunk_frequency(level.hierarchy.chains[0], dt);
            EXPECT_NEAR(f / full, 1.0, 0.05) << level.joint_count() << " joints";
            EXPECT_NEAR(level.frequency_ratio(), 1.0, 0.05) << level.joint_count() << " joints";
        }
    }
}

/// Passes 1-3 in double for one instance at the origin with yaw 0 in a constant wind,
/// written from docs/model.md 3.7 independently of the library: the chains' world rotations.
std::vector<glm::dmat3> step_rotations(const Hierarchy& h, const Parameters& p, const glm::dvec3& wind,
                                       int steps) {
    const size_t chains = h.chains.size();
    std::vector<glm::dmat3> rotation(chains);
    for (size_t c = 0; c < chains; ++c) rotation[c] = glm::dmat3(h.chains[c].frame);  // rest
    std::vector<glm::dvec2> angle(chains, glm::dvec2(0.0)), rate(chains, glm::dvec2(0.0));
    for (int step = 0; step < steps; ++step) {
        std::vector<glm::dmat3> local(chains);
        for (size_t c = 0; c < chains; ++c) {
            const Chain& chain = h.chains[c];
            const glm::dvec3 w = glm::transpose(rotation[c]) * wind;
            const glm::dvec2 g = chain.wind_area * glm::dvec2(w.z, -w.x);
            for (int j = 0; j < 2; ++j) {
                const double force = g[j] - chain.stiffness * angle[c][j] - chain.damping * rate[c][j];
                rate[c][j] += p.dt / chain.inertia * force;
                angle[c][j] += p.dt * rate[c][j];
                if (std::abs(angle[c][j]) > p.max_angle) {
                    angle[c][j] = std::copysign(p.max_angle, angle[c][j]);
                    rate[c][j] = 0.0;
                }
            }
            const double cx = std::cos(angle[c].x), sx = std::sin(angle[c].x);
            const double cz = std::cos(angle[c].y), sz = std::sin(angle[c].y);
            const glm::dmat3 rx(1, 0, 0, 0, cx, sx, 0, -sx, cx), rz(cz, sz, 0, -sz, cz, 0, 0, 0, 1);
            local[c] = glm::dmat3(chain.rest_rotation) * rz * rx;
        }
        for (size_t c = 0; c < chains; ++c)
            rotation[c] = h.chains[c].parent < 0 ? local[c] : rotation[size_t(h.chains[c].parent)] * local[c];
    }
    return rotation;
}

/// A level run as its own model moves each kept chain exactly as the full model moves it:
/// the reference stepper agrees with cpu64 on the full model, and on the level it gives the
/// full model's rotations of the kept chains.
TEST(Levels, KeptChainsMoveAsInTheFullModel) {
    const Model m = preset_model("paper-5");
    SimulationConfig config;
    config.backend = BackendKind::cpu64;
    config.wind.profile = WindProfile::constant;
    config.wind.strength = 9.0;
    config.wind.direction = {1.0, 0.0, 0.4};
    const glm::dvec3 wind = 9.0 * glm::normalize(glm::dvec3(1.0, 0.0, 0.4));
    auto sim = Simulation::create(single_tree_scene(m.tree), config);
    ASSERT_TRUE(sim.ok()) << sim.status().message();
    const int steps = 90;
    ASSERT_TRUE((*sim)->step(steps).ok());
    std::vector<double> rotations;
    ASSERT_TRUE((*sim)->read(Output::chain_rotations, rotations).ok());
    auto close = [&](const glm::dmat3& r, size_t full_chain) {
        double worst = 0.0;
        for (int col = 0; col < 3; ++col)
            for (int row = 0; row < 3; ++row)
                worst = std::max(worst, std::abs(r[col][row] - rotations[9 * full_chain + 3 * size_t(col) + size_t(row)]));
        return worst;
    };
    const auto reference = step_rotations(m.full, config.parameters, wind, steps);
    for (size_t c = 0; c < m.full.chains.size(); ++c) ASSERT_LT(close(reference[c], c), 1e-9) << "chain " << c;
    auto levels = build_levels(m.tree, m.full, config.parameters, {64, 16});
    ASSERT_TRUE(levels.ok());
    bool moved = false;
    for (const DetailLevel& level : *levels) {
        const auto coarse = step_rotations(level.hierarchy, config.parameters, wind, steps);
        for (size_t c = 0; c < coarse.size(); ++c) {
            ASSERT_LT(close(coarse[c], size_t(level.source_chain[c])), 1e-9) << "level chain " << c;
            moved = moved || close(glm::dmat3(level.hierarchy.chains[c].frame), size_t(level.source_chain[c])) > 1e-3;
        }
    }
    EXPECT_TRUE(moved) << "the wind bent no chain: the comparison shows nothing";
}

TEST(Levels, BudgetsAtOrAboveTheChainCountGiveTheFullModel) {
    const Model m = preset_model("paper-5");
    const int32_t chains = int32_t(m.full.chains.size());
    for (int32_t budget : {chains, chains + 1, 100000}) {
        auto level = build_level(m.tree, m.full, {}, budget);
        ASSERT_TRUE(level.ok()) << level.status().message();
        EXPECT_EQ(level->joint_count(), chains);
        EXPECT_EQ(level->geometric_error_m, 0.0);
        for (int32_t c = 0; c < chains; ++c) EXPECT_EQ(level->chain_of[size_t(c)], c);
        EXPECT_EQ(level->hierarchy.node_owner, m.full.node_owner);
    }
    auto one = build_level(m.tree, m.full, {}, chains - 1);
    ASSERT_TRUE(one.ok());
    EXPECT_EQ(one->joint_count(), chains - 1);
}

TEST(Levels, BudgetsBelowTheTrunkOnlyLevelAreRefused) {
    const Model m = preset_model("paper-5");
    for (int32_t budget : {0, -1, -256}) {
        auto level = build_level(m.tree, m.full, {}, budget);
        ASSERT_FALSE(level.ok());
        EXPECT_EQ(level.status().code(), ErrorCode::invalid_argument);
        EXPECT_NE(level.status().message().find("trunk-only"), std::string::npos) << level.status().message();
        EXPECT_NE(level.status().message().find(std::to_string(budget)), std::string::npos);
    }
    auto listed = build_levels(m.tree, m.full, {}, {256, 0, 16});
    ASSERT_FALSE(listed.ok());
    EXPECT_NE(listed.status().message().find("joint budgets[1] = 0"), std::string::npos) << listed.status().message();
    auto empty = build_levels(m.tree, m.full, {}, std::vector<int32_t>{});
    ASSERT_FALSE(empty.ok());
    EXPECT_EQ(empty.status().code(), ErrorCode::invalid_argument);
    auto other = build_hierarchy(test::small_tree(), {}, {});
    ASSERT_TRUE(other.ok());
    auto mismatched = build_level(m.tree, *other, {}, 16);
    ASSERT_FALSE(mismatched.ok());
    EXPECT_EQ(mismatched.status().code(), ErrorCode::invalid_argument);
}

/// A level's skin: weights sum to 1 over existing level joints; at rest it is the full rest
/// mesh; after wind it moves every vertex whose chains the level keeps as pass 7 of the full
/// model does, from the full model's joint matrices of its source chains.
TEST(Levels, LevelSkinIsTheFullMeshAtRestAndFollowsKeptChains) {
    TreeModel tree = *generate_preset("paper-5");
    SimulationConfig config;
    config.backend = BackendKind::cpu;
    config.wind.profile = WindProfile::constant;
    config.wind.strength = 9.0;
    auto sim = Simulation::create(single_tree_scene(tree), config);
    ASSERT_TRUE(sim.ok()) << sim.status().message();
    const Hierarchy& full = (*sim)->hierarchy(0);
    const MeshTemplate& mesh = (*sim)->mesh(0);
    const SkinTemplate full_skin = build_skin(tree, full, mesh, config.model);
    auto levels = build_levels(tree, full, config.parameters, {256, 16, 1});
    ASSERT_TRUE(levels.ok());
    const double height = tree_height(tree);
    for (int round = 0; round < 2; ++round) {
        if (round == 1) ASSERT_TRUE((*sim)->step(120).ok());
        std::vector<float> palette, vertices;
        ASSERT_TRUE((*sim)->read(Output::joint_matrices, palette).ok());
        ASSERT_TRUE((*sim)->read(Output::vertex_positions, vertices).ok());
        for (const DetailLevel& level : *levels) {
            SCOPED_TRACE(std::to_string(level.joint_count()) + " joints, round " + std::to_string(round));
            const SkinTemplate skin = build_skin(tree, full, mesh, config.model, level);
            ASSERT_EQ(skin.vertices.size(), mesh.vertices.size());
            ASSERT_EQ(skin.inverse_bind.size(), size_t(level.joint_count()));
            ASSERT_EQ(skin.source_chains, level.source_chain);
            for (const SkinVertex& v : skin.vertices) {
                EXPECT_NEAR(v.weights[0] + v.weights[1], 1.0, 1e-12);
                EXPECT_GE(v.joints[0], 0);
                EXPECT_LT(v.joints[0], level.joint_count());
                EXPECT_LT(v.joints[1], level.joint_count());
                if (v.joints[1] < 0) EXPECT_EQ(v.weights[1], 0.0);
                else EXPECT_NE(v.joints[1], v.joints[0]);
            }
            std::vector<float> level_palette;
            for (int32_t source : skin.source_chains)
                level_palette.insert(level_palette.end(), palette.begin() + 12 * source, palette.begin() + 12 * source + 12);
            std::vector<float> skinned(3 * mesh.vertices.size());
            ASSERT_TRUE(skin_vertices(skin, level_palette, skinned).ok());
            size_t compared = 0;
            for (size_t i = 0; i < mesh.vertices.size(); ++i) {
                bool kept = true;  // every joint of the full skin is a chain the level keeps
                for (int32_t joint : full_skin.vertices[i].joints)
                    if (joint >= 0) kept = kept && level.source_chain[size_t(level.chain_of[size_t(joint)])] == joint;
                if (round == 1 && !kept) continue;
                ++compared;
                for (int k = 0; k < 3; ++k)
                    ASSERT_NEAR(skinned[3 * i + size_t(k)], vertices[3 * i + size_t(k)], 1e-5 * height) << "vertex " << i;
            }
            EXPECT_GT(compared, 0u);
        }
    }
}

}  // namespace

// Under coupled a chain gathers its children's loads by id (docs/model.md 3.13): every level's
// records name children among the level's own chains (each the level chain whose parent is
// that chain), and the drag a folded subtree's load carried moves into its carrier's wind
// moment, so the trunk-only level's trunk holds the moment of the whole tree's drag about the
// ground, the sum over every chain of its own drag moment brought into the trunk's frame.
TEST(Levels, CoupledLevelsNameTheirOwnChildrenAndKeepTheFoldedDrag) {
    const TreeModel tree = test::deep_tree(5);
    ModelOptions options;
    options.dynamics = Dynamics::coupled;
    auto full = build_hierarchy(tree, options, {});
    ASSERT_TRUE(full.ok()) << full.status().message();
    const int32_t chains = int32_t(full->chains.size());
    ASSERT_GT(chains, 6);
    // Each chain's own drag moment (its wind moment less its children's subtree drag at their
    // attach nodes), in the trunk's frame, summed over the tree.
    std::vector<glm::dmat3> to_trunk(static_cast<size_t>(chains), glm::dmat3(1.0));
    glm::dvec3 whole(0.0);
    for (int32_t c = 0; c < chains; ++c) {
        const Chain& chain = full->chains[size_t(c)];
        to_trunk[size_t(c)] = c == 0 ? glm::dmat3(1.0) : to_trunk[size_t(chain.parent)] * glm::dmat3(chain.rest_rotation);
        glm::dvec3 own(chain.dynamics.wind_moment);
        const glm::dvec3 attach(tree.nodes[size_t(chain.attach_node)].position);
        for (int32_t k = chain.dynamics.first_child; k < chain.dynamics.first_child + chain.dynamics.child_count; ++k) {
            const Chain& child = full->chains[size_t(k)];
            const glm::dvec3 arm = glm::transpose(glm::dmat3(chain.frame)) *
                                   (glm::dvec3(tree.nodes[size_t(child.attach_node)].position) - attach);
            own -= child.dynamics.subtree_drag_area * arm;
        }
        // Brought to the trunk's joint: the chain's drag at its attach node's lever too.
        const glm::dvec3 base(tree.nodes[size_t(full->chains[0].attach_node)].position);
        const glm::dvec3 lever = glm::transpose(glm::dmat3(full->chains[0].frame)) * (attach - base);
        whole += to_trunk[size_t(c)] * own + (c == 0 ? 0.0 : chain.dynamics.drag_area) * lever;
    }
    for (int32_t budget = chains; budget >= 1; --budget) {
        SCOPED_TRACE("budget " + std::to_string(budget));
        auto level = build_level(tree, *full, {}, budget);
        ASSERT_TRUE(level.ok()) << level.status().message();
        const auto& h = level->hierarchy.chains;
        for (size_t c = 0; c < h.size(); ++c) {
            const ChainDynamics& d = h[c].dynamics;
            int32_t children = 0;
            for (size_t k = 0; k < h.size(); ++k) children += h[k].parent == int32_t(c);
            ASSERT_EQ(d.child_count, children) << "chain " << c;
            for (int32_t k = d.first_child; k < d.first_child + d.child_count; ++k) {
                ASSERT_LT(size_t(k), h.size()) << "chain " << c << " names a child past the level";
                EXPECT_EQ(h[size_t(k)].parent, int32_t(c)) << "chain " << c;
            }
        }
        if (budget == 1) {
            const glm::dvec3 trunk(h[0].dynamics.wind_moment);
            EXPECT_LT(glm::length(trunk - whole), 1e-9 * glm::length(whole))
                << "trunk-only level's wind moment (" << trunk.x << ", " << trunk.y << ", " << trunk.z << ") against the tree's ("
                << whole.x << ", " << whole.y << ", " << whole.z << ")";
        }
        if (budget == chains) {
            for (size_t c = 0; c < h.size(); ++c)
                EXPECT_EQ(glm::dvec3(h[c].dynamics.wind_moment), glm::dvec3(full->chains[c].dynamics.wind_moment));
        }
    }
}
