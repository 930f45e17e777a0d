// Stable instance handles (docs/driving.md): ids 0..n-1 for the scene's instances, the next
// unused id for each added one; valid across removals of others, never reused; a removed,
// unknown or repeated id is refused, naming it, and changes nothing.
#include "test_trees.h"

#include <gtest/gtest.h>

namespace hmsm {
namespace {

std::vector<InstanceId> ids(std::initializer_list<uint64_t> values) {
    std::vector<InstanceId> out;
    for (uint64_t v : values) out.push_back(InstanceId(v));
    return out;
}

std::unique_ptr<Simulation> five_trees() {
    SimulationConfig config;
    config.backend = BackendKind::cpu;
    config.wind.profile = WindProfile::y4;
    config.wind.strength = 6.0;
    auto sim = Simulation::create(*grid_scene(test::small_tree(), 5, 6.0, 3), config);
    EXPECT_TRUE(sim.ok()) << sim.status().message();
    return sim ? std::move(sim).value() : nullptr;
}

void expect_ids(const Simulation& sim, const std::vector<InstanceId>& expected) {
    ASSERT_EQ(std::vector<InstanceId>(sim.instance_ids().begin(), sim.instance_ids().end()), expected);
    for (uint64_t i = 0; i < expected.size(); ++i) {
        EXPECT_EQ(sim.index_of(expected[i]).value(), i);
        EXPECT_EQ(sim.id_of(i).value(), expected[i]);
    }
}

/// A refused call: an invalid_argument naming `fragment`, and the instance list, its ids and
/// every output as they were.
template <class Call>
void expect_refused_unchanged(Simulation& sim, Call call, const std::string& fragment) {
    const std::vector<InstanceId> ids_before(sim.instance_ids().begin(), sim.instance_ids().end());
    std::vector<float> nodes_before, nodes_after;
    ASSERT_TRUE(sim.read(Output::node_positions, nodes_before).ok());
    const Status status = call();
    ASSERT_FALSE(status.ok());
    EXPECT_EQ(status.code(), ErrorCode::invalid_argument);
    EXPECT_NE(status.message().find(fragment), std::string::npos) << status.message();
    EXPECT_EQ(std::vector<InstanceId>(sim.instance_ids().begin(), sim.instance_ids().end()), ids_before);
    ASSERT_TRUE(sim.read(Output::node_positions, nodes_after).ok());
    EXPECT_EQ(nodes_after, nodes_before);
}

TEST(InstanceHandles, SurviveRemovalsAndAreNeverReused) {
    auto sim = five_trees();
    ASSERT_TRUE(sim);
    expect_ids(*sim, ids({0, 1, 2, 3, 4}));
    ASSERT_TRUE(sim->step(10).ok());
    const uint64_t gone[] = {1, 3};
    ASSERT_TRUE(sim->remove_instances(gone).ok());
    expect_ids(*sim, ids({0, 2, 4}));

    const Instance added[] = {{0, {30, 0, 0}, 0.1}, {0, {36, 0, 0}, 0.2}};
    std::vector<InstanceId> given(2);
    ASSERT_TRUE(sim->add_instances(added, given).ok());
    EXPECT_EQ(given, ids({5, 6}));
    expect_ids(*sim, ids({0, 2, 4, 5, 6}));
    EXPECT_EQ(sim->instances()[sim->index_of(InstanceId(6)).value()].origin, glm::dvec3(36, 0, 0));

    ASSERT_TRUE(sim->remove_instances_by_id(ids({6, 0})).ok());
    expect_ids(*sim, ids({2, 4, 5}));
    const uint32_t reset[] = {1};
    ASSERT_TRUE(sim->reset_instances(reset).ok());
    ASSERT_TRUE(sim->step(3).ok());
    expect_ids(*sim, ids({2, 4, 5}));
    ASSERT_TRUE(sim->add_instances(std::span(added, 1)).ok());  // the call without ids
    expect_ids(*sim, ids({2, 4, 5, 7}));                         // 6 is not given again
}

TEST(InstanceHandles, BadHandlesChangeNothing) {
    auto sim = five_trees();
    ASSERT_TRUE(sim);
    ASSERT_TRUE(sim->step(8).ok());
    ASSERT_TRUE(sim->remove_instances_by_id(ids({3})).ok());
    EXPECT_EQ(sim->index_of(InstanceId(3)).status().message(), "instance id 3 was removed");
    EXPECT_NE(sim->index_of(InstanceId(99)).status().message().find("instance id 99 was never given"),
              std::string::npos);
    EXPECT_FALSE(sim->id_of(4).ok());
    EXPECT_NE(sim->id_of(4).status().message().find("instance 4"), std::string::npos);

    expect_refused_unchanged(*sim, [&] { return sim->remove_instances_by_id(ids({0, 3})); }, "instance id 3 was removed");
    expect_refused_unchanged(*sim, [&] { return sim->remove_instances_by_id(ids({1, 99})); }, "instance id 99");
    expect_refused_unchanged(*sim, [&] { return sim->remove_instances_by_id(ids({2, 4, 2})); },
                             "instance id 2 is listed twice");
    expect_refused_unchanged(*sim, [&] { return sim->remove_instances_by_id(ids({0, 1, 2, 4})); }, "every instance");
    const Instance one[] = {{0, {40, 0, 0}, 0.0}};
    std::vector<InstanceId> no_room;
    expect_refused_unchanged(*sim, [&] { return sim->add_instances(one, no_room); }, "room for 0 ids");
    expect_ids(*sim, ids({0, 1, 2, 4}));
}

// A swap removal fills each hole below the new count with the survivors past it, in order; the
// handles follow; additions then append with fresh ids; bad ids change nothing.
TEST(InstanceHandles, FollowSwapRemovals) {
    auto sim = five_trees();
    ASSERT_TRUE(sim);
    ASSERT_TRUE(sim->step(6).ok());
    const glm::dvec3 last_origin = sim->instances()[4].origin;
    ASSERT_TRUE(sim->swap_remove_instances(ids({1})).ok());
    expect_ids(*sim, ids({0, 4, 2, 3}));
    EXPECT_EQ(sim->instances()[1].origin, last_origin);
    expect_refused_unchanged(*sim, [&] { return sim->swap_remove_instances(ids({0, 1})); },
                             "instance id 1 was removed");
    expect_refused_unchanged(*sim, [&] { return sim->swap_remove_instances(ids({5})); },
                             "instance id 5 was never given");
    expect_refused_unchanged(*sim, [&] { return sim->swap_remove_instances(ids({4, 4})); },
                             "instance id 4 is listed twice");
    expect_refused_unchanged(*sim, [&] { return sim->swap_remove_instances(ids({0, 4, 2, 3})); }, "every instance");
    ASSERT_TRUE(sim->swap_remove_instances(ids({0, 3})).ok());  // hole 0 takes id 2, id 3 was last
    expect_ids(*sim, ids({2, 4}));
    const Instance added[] = {{0, {30, 0, 0}, 0.1}};
    ASSERT_TRUE(sim->add_instances(added).ok());
    expect_ids(*sim, ids({2, 4, 5}));
    ASSERT_TRUE(sim->remove_instances_by_id(ids({4})).ok());
    expect_ids(*sim, ids({2, 5}));
    ASSERT_TRUE(sim->step(3).ok());
}

}  // namespace
}  // namespace hmsm
