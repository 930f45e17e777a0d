// Levels of detail run as models of a simulation (Scene::joint_budgets, docs/model.md 3.12): a
// level shares the dispatches of the whole model, its kept chains move as the model's on every
// backend, the backends agree with cpu64 on it, and its mesh is the level skin of the model's.
#include "test_trees.h"

#include <hmsm/hmsm_c.h>
#include <hmsm/levels.h>
#include <hmsm/skin.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

using namespace hmsm;

namespace {

/// paper-5 three times, whole, at 64 joints and trunk-only, one instance each at the origin.
Scene levels_scene() {
    const TreeModel tree = *generate_preset("paper-5");
    Scene scene;
    scene.models = {tree, tree, tree};
    scene.model_names = {"whole", "64", "trunk"};
    scene.joint_budgets = {0, 64, 1};
    for (uint32_t m = 0; m < 3; ++m) scene.instances.push_back(Instance{m});
    return scene;
}

SimulationConfig windy(BackendKind kind) {
    SimulationConfig config;
    config.backend = kind;
    config.wind.profile = WindProfile::y1;
    config.wind.strength = 9.0;
    config.wind.direction = {1.0, 0.0, 0.5};
    return config;
}

class LevelSimulation : public ::testing::TestWithParam<BackendKind> {};

TEST_P(LevelSimulation, KeptChainsMoveAsTheWholeModelAndBackendsAgreeWithCpu64) {
    const Scene scene = levels_scene();
    std::string skip;
    auto sim = test::create_simulation_or_skip(scene, windy(GetParam()), GetParam(), skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    auto oracle = test::create_simulation_or_skip(scene, windy(BackendKind::cpu64), BackendKind::cpu64, skip);
    ASSERT_TRUE(sim && oracle);
    const Hierarchy& whole = sim->hierarchy(0);
    ASSERT_EQ(sim->hierarchy(1).chains.size(), 64u);
    ASSERT_EQ(sim->hierarchy(2).chains.size(), 1u);
    auto level = build_level(scene.models[0], whole, sim->config().parameters, 64);
    ASSERT_TRUE(level.ok());
    const double height = tree_height(scene.models[0]);
    const bool exact = GetParam() == BackendKind::cpu64;
    const SkinTemplate skin = build_skin(scene.models[0], whole, sim->mesh(0), sim->config().model, *level);

    for (int round = 0; round < 2; ++round) {
        SCOPED_TRACE(round == 0 ? "at rest" : "after 150 steps");
        if (round == 1) {
            ASSERT_TRUE(sim->step(150).ok());
            ASSERT_TRUE(oracle->step(150).ok());
        }
        const auto rotations = test::read_output(*sim, Output::chain_rotations);
        const size_t chains = whole.chains.size();
        ASSERT_EQ(rotations.size(), 9 * (chains + 64 + 1));
        double moved = 0.0;
        for (size_t c = 0; c < 64; ++c) {
            const size_t source = size_t(level->source_chain[c]);
            for (size_t k = 0; k < 9; ++k) {
                ASSERT_NEAR(rotations[9 * (chains + c) + k], rotations[9 * source + k], exact ? 1e-12 : 1e-5)
                    << "level chain " << c;
                moved = std::max(moved, std::abs(rotations[9 * source + k] - glm::dmat3(whole.chains[source].frame)[k / 3][k % 3]));
            }
        }
        for (size_t k = 0; k < 9; ++k) ASSERT_NEAR(rotations[9 * (chains + 64) + k], rotations[k], exact ? 1e-12 : 1e-5);
        if (round == 1) EXPECT_GT(moved, 1e-3) << "the wind must bend the kept chains";

        // The level's mesh is the level skin driven by the whole model's kept chains.
        const auto joints = test::read_output(*sim, Output::joint_matrices);
        const auto vertices = test::read_output(*sim, Output::vertex_positions);
        std::vector<float> palette;
        for (int32_t source : skin.source_chains)
            for (size_t k = 0; k < 12; ++k) palette.push_back(float(joints[12 * size_t(source) + k]));
        std::vector<float> skinned(3 * skin.vertices.size());
        ASSERT_TRUE(skin_vertices(skin, palette, skinned).ok());
        const size_t offset = 3 * sim->mesh(0).vertices.size();
        ASSERT_EQ(sim->mesh(1).vertices.size(), skin.vertices.size());
        for (size_t i = 0; i < skinned.size(); ++i)
            ASSERT_NEAR(vertices[offset + i], skinned[i], 1e-5 * height) << "level vertex " << i / 3;

        // Every backend agrees with cpu64 on the levels' nodes and vertices.
        for (Output output : {Output::node_positions, Output::vertex_positions}) {
            const auto got = test::read_output(*sim, output), expected = test::read_output(*oracle, output);
            ASSERT_EQ(got.size(), expected.size());
            EXPECT_LT(test::max_abs_difference(got, expected), 1e-4 * height) << (output == Output::node_positions ? "nodes" : "vertices");
        }
    }
}

INSTANTIATE_TEST_SUITE_P(Backends, LevelSimulation,
                         ::testing::Values(BackendKind::cpu64, BackendKind::cpu, BackendKind::cpu_parallel,
                                           BackendKind::vulkan, BackendKind::cuda),
                         test::BackendTestName());

TEST(LevelSimulation, BadJointBudgetsAreRefused) {
    Scene scene = levels_scene();
    scene.joint_budgets = {0, -2, 1};
    auto negative = Simulation::create(scene, windy(BackendKind::cpu64));
    ASSERT_FALSE(negative.ok());
    EXPECT_NE(negative.status().message().find("joint budget -2"), std::string::npos) << negative.status().message();
    scene.joint_budgets = {0, 1, 1, 1};
    auto longer = Simulation::create(scene, windy(BackendKind::cpu64));
    ASSERT_FALSE(longer.ok());
    EXPECT_EQ(longer.status().code(), ErrorCode::invalid_argument);
    scene.joint_budgets = {100000};  // at or above the chain count: the model whole
    auto whole = Simulation::create(scene, windy(BackendKind::cpu64));
    ASSERT_TRUE(whole.ok()) << whole.status().message();
    EXPECT_EQ((*whole)->hierarchy(0).chains.size(), (*whole)->hierarchy(1).chains.size());
}

/// The C ABI's hmsm_scene_set_joint_budget: the level's chains in the counts, bad calls refused.
TEST(LevelSimulation, CSceneSetsAJointBudget) {
    hmsm_tree* tree = nullptr;
    hmsm_scene* scene = nullptr;
    ASSERT_EQ(hmsm_tree_preset("paper-5", 0, &tree), HMSM_OK);
    ASSERT_EQ(hmsm_scene_create(&scene), HMSM_OK);
    uint32_t model = 0;
    ASSERT_EQ(hmsm_scene_add_model(scene, tree, "whole", &model), HMSM_OK);
    ASSERT_EQ(hmsm_scene_add_model(scene, tree, "coarse", &model), HMSM_OK);
    hmsm_instance instance;
    ASSERT_EQ(HMSM_INIT(hmsm_instance_init, &instance), HMSM_OK);
    ASSERT_EQ(hmsm_scene_add_instance(scene, &instance), HMSM_OK);
    instance.model = model;
    ASSERT_EQ(hmsm_scene_add_instance(scene, &instance), HMSM_OK);
    EXPECT_EQ(hmsm_scene_set_joint_budget(scene, 1, -1), HMSM_INVALID_ARGUMENT);
    EXPECT_NE(std::string(hmsm_status_message()).find("max_joints -1"), std::string::npos);
    EXPECT_EQ(hmsm_scene_set_joint_budget(scene, 2, 16), HMSM_INVALID_ARGUMENT);
    EXPECT_EQ(hmsm_scene_set_joint_budget(nullptr, 0, 16), HMSM_INVALID_ARGUMENT);
    ASSERT_EQ(hmsm_scene_set_joint_budget(scene, 1, 16), HMSM_OK);
    hmsm_config config;
    ASSERT_EQ(HMSM_INIT(hmsm_config_init, &config), HMSM_OK);
    config.backend = HMSM_BACKEND_CPU64;
    hmsm_simulation* sim = nullptr;
    ASSERT_EQ(hmsm_simulation_create(scene, &config, &sim), HMSM_OK) << hmsm_status_message();
    hmsm_counts counts;
    ASSERT_EQ(HMSM_INIT(hmsm_counts_init, &counts), HMSM_OK);
    ASSERT_EQ(hmsm_simulation_counts(sim, &counts), HMSM_OK);
    EXPECT_EQ(counts.chains, 393u + 16u);
    hmsm_simulation_destroy(sim);
    hmsm_scene_destroy(scene);
    hmsm_tree_destroy(tree);
}

}  // namespace
