// Simulation::reset_instances (docs/driving.md): a NaN'd or violently moving instance returns
// exactly to the rest state of a fresh simulation, every other instance untouched, on every
// backend; bad indices are refused and change nothing.
#include "test_trees.h"

#include "simulation_access.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace hmsm {
namespace {

bool any_nan(const std::vector<std::vector<float>>& values) {
    for (const auto& v : values)
        for (float x : v)
            if (std::isnan(x)) return true;
    return false;
}

class ResetInstances : public ::testing::TestWithParam<BackendKind> {};

TEST_P(ResetInstances, ReturnsExactlyToRestOthersUntouched) {
    Scene scene = single_tree_scene(test::small_tree());
    for (double x : {6.0, 12.0}) scene.instances.push_back({0, Vec3(x, 0.0, 0.0), 0.3 * x});
    scene.instances[2].active = false;  // a paused instance is reset too and stays paused
    SimulationConfig config;
    config.wind.profile = WindProfile::y1;
    config.wind.strength = 60.0;
    std::string skip;
    auto fresh = test::create_simulation_or_skip(scene, config, GetParam(), skip);
    if (!fresh) GTEST_SKIP() << skip;
    auto sim = test::create_simulation_or_skip(scene, config, GetParam(), skip);
    ASSERT_TRUE(sim);

    const auto rest = test::outputs_by_instance(*fresh);
    auto now = [&] { return test::outputs_by_instance(*sim); };
    ASSERT_TRUE(sim->step(40).ok());
    ASSERT_TRUE(sim->set_instance_active(2, true).ok());
    ASSERT_TRUE(sim->step(10).ok());
    ASSERT_TRUE(sim->set_instance_active(2, false).ok());
    // Instance 1's state turned to NaN (as an engine's own bad numbers would): it spreads to
    // every output of that instance within a step.
    const uint64_t chains = sim->chain_count() / 3;
    const std::vector<double> nan(chains * 4, std::numeric_limits<double>::quiet_NaN());
    ASSERT_TRUE(detail::backend_of(*sim).write(detail::BufferId::chain_state, chains, chains, nan.data(),
                                               detail::Scalar::f64).ok());
    ASSERT_TRUE(sim->step(3).ok());
    ASSERT_TRUE(any_nan(now()[1]));
    const auto moving = now()[0], paused = now()[2];
    ASSERT_FALSE(test::same_bits(moving, rest[0]));
    ASSERT_FALSE(test::same_bits(paused, rest[2]));

    // Refused: nothing changes.
    for (std::vector<uint32_t> bad : {std::vector<uint32_t>{1, 3}, std::vector<uint32_t>{0, 0}}) {
        Status refused = sim->reset_instances(bad);
        EXPECT_EQ(refused.code(), ErrorCode::invalid_argument);
        EXPECT_TRUE(any_nan(now()[1]));
        EXPECT_TRUE(test::same_bits(now()[0], moving));
    }
    EXPECT_NE(sim->reset_instances(std::vector<uint32_t>{1, 3}).message().find("instance 3"), std::string::npos);

    ASSERT_TRUE(sim->reset_instances(std::vector<uint32_t>{1}).ok());
    EXPECT_TRUE(test::same_bits(now()[1], rest[1]));
    EXPECT_TRUE(test::same_bits(now()[0], moving));
    EXPECT_TRUE(test::same_bits(now()[2], paused));

    ASSERT_TRUE(sim->reset_instances(std::vector<uint32_t>{2, 0}).ok());
    const auto after = now();
    for (uint64_t i = 0; i < 3; ++i) EXPECT_TRUE(test::same_bits(after[i], rest[i])) << "instance " << i;
    EXPECT_FALSE(sim->instances()[2].active);

    // From rest the reset instances move on, finite.
    ASSERT_TRUE(sim->set_instance_active(2, true).ok());
    ASSERT_TRUE(sim->step(5).ok());
    EXPECT_FALSE(any_nan(now()[1]));
}

INSTANTIATE_TEST_SUITE_P(Backends, ResetInstances,
                         ::testing::Values(BackendKind::cpu, BackendKind::cpu64, BackendKind::cpu_parallel,
                                           BackendKind::vulkan, BackendKind::cuda),
                         test::BackendTestName());

}  // namespace
}  // namespace hmsm
