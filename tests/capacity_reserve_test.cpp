// Room reserved up front for a world of levels of detail (src/capacity_reserve.cpp,
// Simulation::reserve_instances(per_level)): instances added and switched among the levels
// within the room never grow the capacity, the results equal those of a simulation that grows
// as it goes, bit for bit, and the room is much smaller than room for every instance at its full
// level; bad level counts are refused with one clear error and change nothing.
#include "test_trees.h"

#include "simulation_access.h"

#include <gtest/gtest.h>

namespace hmsm {
namespace {

using detail::device_growths_of;
using detail::full_uploads_of;

/// Two models with levels 0-3, four trees that start on the coarsest.
Scene level_scene() {
    Scene scene = test::small_and_deep_with_levels(3);
    for (Instance& instance : scene.instances) instance.level = 3;
    return scene;
}

class CapacityReserve : public ::testing::TestWithParam<BackendKind> {};

TEST_P(CapacityReserve, LevelRoomHoldsAWorldOfLevelsWithoutGrowing) {
    std::string skip;
    SimulationConfig config = test::windy_config();
    config.instance_layout = InstanceLayout::placed;  // as an open world streams
    auto reserved = test::create_simulation_or_skip(level_scene(), config, GetParam(), skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    auto growing = test::create_simulation_or_skip(level_scene(), config, GetParam(), skip);
    auto whole = test::create_simulation_or_skip(level_scene(), config, GetParam(), skip);
    ASSERT_TRUE(reserved && growing && whole);
    // Room for 76 trees: 3 on the full level, 5, 8 and 60 on the coarser ones (4 there now).
    const uint64_t per_level[] = {3, 5, 8, 60};
    ASSERT_TRUE(reserved->reserve_instances(per_level).ok());
    ASSERT_TRUE(whole->reserve_instances(76).ok());
    const uint64_t growths = device_growths_of(*reserved), uploads = full_uploads_of(*reserved);
    const detail::SceneData& room = detail::scene_data_of(*reserved);
    EXPECT_GE(room.instance_capacity, 76u);
    EXPECT_LT(room.chain_capacity * 2, detail::scene_data_of(*whole).chain_capacity)
        << "room at the levels asked for is less than half of room for every tree at its full level";

    Simulation* sims[] = {reserved.get(), growing.get()};
    for (Simulation* sim : sims) ASSERT_TRUE(sim->step(10).ok());
    const uint32_t counts[] = {2, 5, 8, 16};
    for (uint32_t level = 0; level < 4; ++level) {
        std::vector<Instance> added;
        for (uint32_t k = 0; k < counts[level]; ++k) {
            Instance tree{k % 2, {-15.0 + 3.0 * k, 0.0, 7.0 * (level + 1)}, 0.2 * k, 0.9, 0.1 * level};
            tree.level = level;
            added.push_back(tree);
        }
        for (Simulation* sim : sims) ASSERT_TRUE(sim->add_instances(added).ok());
        for (Simulation* sim : sims) ASSERT_TRUE(sim->step(4).ok());
    }
    // Two trees trade levels (full and coarsest), then the world steps on: the one turning
    // coarse fades, running both levels for a while, in the room of the third full tree.
    const InstanceId pair[] = {reserved->instance_ids()[4], reserved->instance_ids()[0]};
    const uint32_t traded[] = {3, 0};
    for (Simulation* sim : sims) ASSERT_TRUE(sim->set_instance_lods(pair, traded).ok());
    for (Simulation* sim : sims) ASSERT_TRUE(sim->step(30).ok());
    EXPECT_EQ(reserved->instance_count(), 35u);
    EXPECT_EQ(device_growths_of(*reserved), growths) << "every change fitted the room";
    EXPECT_EQ(full_uploads_of(*reserved), uploads);
    EXPECT_GE(device_growths_of(*growing) + full_uploads_of(*growing), 1u) << "without the room the world grows";
    EXPECT_TRUE(test::same_bits(test::every_output(*reserved), test::every_output(*growing)));
    // Full trees past the room grow it.
    const std::vector<Instance> more(12, Instance{0, {30, 0, 30}, 0.5});
    ASSERT_TRUE(reserved->add_instances(more).ok());
    EXPECT_GT(device_growths_of(*reserved) + full_uploads_of(*reserved), growths + uploads);
}

// The counts are checked on the host, before any backend work: the CPU backend shows it.
TEST(CapacityReserveInput, BadLevelCountsAreRefusedAndChangeNothing) {
    std::string skip;
    auto sim = test::create_simulation_or_skip(level_scene(), test::windy_config(), BackendKind::cpu, skip);
    ASSERT_TRUE(sim) << skip;
    const struct {
        uint64_t chains, nodes, instances;
    } before{detail::scene_data_of(*sim).chain_capacity, detail::scene_data_of(*sim).node_capacity,
             detail::scene_data_of(*sim).instance_capacity};
    auto unchanged = [&](const std::string& why) {
        const detail::SceneData& d = detail::scene_data_of(*sim);
        EXPECT_EQ(d.chain_capacity, before.chains) << why;
        EXPECT_EQ(d.node_capacity, before.nodes) << why;
        EXPECT_EQ(d.instance_capacity, before.instances) << why;
        EXPECT_EQ(device_growths_of(*sim) + full_uploads_of(*sim), 0u) << why;
    };
    const Status none = sim->reserve_instances(std::span<const uint64_t>());
    EXPECT_EQ(none.code(), ErrorCode::invalid_argument);
    EXPECT_NE(none.message().find("no level counts"), std::string::npos) << none.message();
    unchanged("no counts");
    const uint64_t five[] = {1, 1, 1, 1, 1};
    const Status past = sim->reserve_instances(five);
    EXPECT_EQ(past.code(), ErrorCode::invalid_argument);
    EXPECT_NE(past.message().find("5 level counts"), std::string::npos) << past.message();
    EXPECT_NE(past.message().find("at most 4 levels"), std::string::npos) << past.message();
    unchanged("more counts than levels");
    const uint64_t many[] = {0, kMaxInstances, 1};
    const Status too_many = sim->reserve_instances(many);
    EXPECT_EQ(too_many.code(), ErrorCode::unsupported);
    EXPECT_NE(too_many.message().find("level 2"), std::string::npos) << too_many.message();
    unchanged("past kMaxInstances");
    // A refused reserve leaves no room behind: an add past the capacity grows by half only.
    std::vector<Instance> added(3, Instance{0, {20, 0, 0}, 0.1});
    for (Instance& tree : added) tree.level = 3;
    ASSERT_TRUE(sim->add_instances(added).ok());
    EXPECT_LT(detail::scene_data_of(*sim).instance_capacity, 100u);
}

// The GPU backends, whose level switches stage templates only (a CPU backend stages the
// switched trees' state as well: reserve them a margin, simulation.h).
INSTANTIATE_TEST_SUITE_P(Backends, CapacityReserve, ::testing::Values(BackendKind::vulkan, BackendKind::cuda),
                         test::BackendTestName());

}  // namespace
}  // namespace hmsm
