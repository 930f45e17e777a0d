// Adding and removing instances in place (docs/driving.md): within the allocated capacity no
// add or remove re-uploads the scene; survivors keep their state bit for bit; the result equals
// the path that uploads the scene anew; added instances beyond the capacity grow it once.
#include "test_trees.h"

#include "backend.h"
#include "forwarding_backend.h"
#include "simulation_access.h"

#include <gtest/gtest.h>

namespace hmsm {
namespace {

using detail::device_growths_of;
using detail::full_uploads_of;
using detail::scene_data_of;

Scene two_model_forest() {
    Scene scene = *grid_scene(test::small_tree(), 7, 5.0, 11);
    scene.models.push_back(test::deep_tree(4));
    scene.model_names.push_back("deep");
    scene.instances.insert(scene.instances.begin() + 3, Instance{1, {-6, 0, 8}, 0.4});
    scene.instances.push_back({1, {9, 0, -3}, 1.9, 0.7, 0.3});
    scene.instances[5].active = false;
    return scene;
}

/// A backend that cannot reshape in place: every add and remove takes the upload path.
class UploadsAnew final : public test::ForwardingBackend {
public:
    using ForwardingBackend::ForwardingBackend;
    Status move_elements(detail::BufferId, std::span<const detail::ElementMove>) override {
        return {ErrorCode::internal, "UploadsAnew moves nothing"};
    }
    Status move_buffers(std::span<const detail::BufferMoves>) override {
        return {ErrorCode::internal, "UploadsAnew moves nothing"};
    }
    detail::BackendCapabilities capabilities() const override {
        detail::BackendCapabilities can = ForwardingBackend::capabilities();
        can.reshapes_in_place = false;
        return can;
    }
};

class LiveReshape : public ::testing::TestWithParam<BackendKind> {
protected:
    std::unique_ptr<Simulation> create(const Scene& scene, bool in_place, std::string& skip) {
        auto sim = test::create_simulation_or_skip(scene, test::windy_config(), GetParam(), skip);
        if (!sim || in_place) return sim;
        // The same backend kind behind a wrapper that refuses to reshape in place.
        auto backend = detail::create_backend(GetParam());
        if (!backend) return nullptr;
        auto anew = detail::SimulationAccess::create(
            scene, test::windy_config(), std::make_unique<UploadsAnew>(std::move(backend).value()));
        EXPECT_TRUE(anew.ok()) << anew.status().message();
        return anew ? std::move(anew).value() : nullptr;
    }
};

// Removal moves the survivors' state on the device: no upload, every survivor's outputs bit for
// bit what they were, inactive ones included.
TEST_P(LiveReshape, RemovalKeepsSurvivorsBitwiseWithoutUpload) {
    std::string skip;
    auto sim = create(two_model_forest(), true, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(sim);
    ASSERT_TRUE(sim->step(25).ok());
    const auto before = test::outputs_by_instance(*sim);
    const uint64_t gone[] = {0, 4, 6};
    ASSERT_TRUE(sim->remove_instances(gone).ok());
    EXPECT_EQ(full_uploads_of(*sim), 0u);
    const auto after = test::outputs_by_instance(*sim);
    const size_t survivors[] = {1, 2, 3, 5, 7, 8};
    ASSERT_EQ(sim->instance_count(), std::size(survivors));
    for (size_t k = 0; k < std::size(survivors); ++k)
        for (size_t o = 0; o < std::size(test::kEveryOutput); ++o)
            EXPECT_EQ(after[k][o], before[survivors[k]][o]) << "output " << o << ", survivor " << survivors[k];
}

// Removing and adding in place gives bitwise what uploading the scene anew gives, through
// further steps, several changes and both models.
TEST_P(LiveReshape, InPlaceEqualsUploadingAnew) {
    std::string skip;
    auto in_place = create(two_model_forest(), true, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    auto anew = create(two_model_forest(), false, skip);
    ASSERT_TRUE(in_place && anew);
    auto change = [](Simulation& sim, int round) {
        const uint64_t gone[] = {uint64_t(round), 3};
        ASSERT_TRUE(sim.remove_instances(gone).ok());
        const Instance added[] = {{1, {12, 0, double(round)}, 0.2 * round}, {0, {-9, 0, 4}, 1.0, 0.5, 0.1}};
        ASSERT_TRUE(sim.add_instances(added).ok());
        ASSERT_TRUE(sim.set_instance_active(2, round % 2 == 0).ok());
    };
    for (int round = 0; round < 3; ++round) {
        ASSERT_TRUE(in_place->step(15).ok());
        ASSERT_TRUE(anew->step(15).ok());
        change(*in_place, round);
        change(*anew, round);
        EXPECT_EQ(test::every_output(*in_place), test::every_output(*anew)) << "right after round " << round;
    }
    ASSERT_TRUE(in_place->step(20).ok());
    ASSERT_TRUE(anew->step(20).ok());
    EXPECT_EQ(test::every_output(*in_place), test::every_output(*anew));
    EXPECT_EQ(full_uploads_of(*in_place), 0u) << "every change fitted the capacity";
    EXPECT_EQ(full_uploads_of(*anew), 6u);
}

// Adding past the capacity grows it once by half, on the device where the backend can (else
// by uploading the scene anew), so that the next adds fit; removing never gives memory back.
TEST_P(LiveReshape, AddingPastTheCapacityGrowsItOnce) {
    std::string skip;
    auto sim = create(two_model_forest(), true, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(sim);
    ASSERT_TRUE(sim->step(5).ok());
    const bool on_device = detail::backend_of(*sim).capabilities().grows_on_device;
    auto growths = [&] { return full_uploads_of(*sim) + device_growths_of(*sim); };
    const uint64_t chains = scene_data_of(*sim).chain_capacity;
    const Instance one[] = {{0, {30, 0, 0}, 0.5}};
    ASSERT_TRUE(sim->add_instances(one).ok());
    EXPECT_EQ(growths(), 1u);
    EXPECT_EQ(full_uploads_of(*sim), on_device ? 0u : 1u);
    EXPECT_GE(scene_data_of(*sim).chain_capacity, chains + chains / 2);
    ASSERT_TRUE(sim->step(5).ok());
    for (int k = 0; k < 3; ++k) ASSERT_TRUE(sim->add_instances(one).ok());
    EXPECT_EQ(growths(), 1u) << "the grown capacity holds three more";
    const uint64_t gone[] = {0, 1, 2, 3, 4};
    ASSERT_TRUE(sim->remove_instances(gone).ok());
    EXPECT_EQ(growths(), 1u);
    ASSERT_TRUE(sim->step(10).ok());
    std::vector<float> nodes;
    ASSERT_TRUE(sim->read(Output::node_positions, nodes).ok());
    EXPECT_TRUE(test::all_finite(std::vector<double>(nodes.begin(), nodes.end())));
}

// Added instances start at rest wherever they land, also in space a removed instance left.
TEST_P(LiveReshape, AddedInstancesStartAtRest) {
    std::string skip;
    auto sim = create(two_model_forest(), true, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(sim);
    ASSERT_TRUE(sim->step(30).ok());
    const uint64_t gone[] = {1, 2};
    ASSERT_TRUE(sim->remove_instances(gone).ok());
    const Instance added[] = {{0, {0, 0, 0}, 0.0}};
    ASSERT_TRUE(sim->add_instances(added).ok());
    EXPECT_EQ(full_uploads_of(*sim), 0u);
    std::vector<float> angles;
    ASSERT_TRUE(sim->read(Output::chain_angles, angles).ok());
    const size_t last = sim->instance_count() - 1;
    const auto chains = test::first_elements(*sim, Output::chain_angles);
    for (float a : test::instance_slice(angles, chains, last, Output::chain_angles)) EXPECT_EQ(a, 0.0f);
    // Its nodes are the model's rest pose at the origin.
    std::vector<float> nodes;
    ASSERT_TRUE(sim->read(Output::node_positions, nodes).ok());
    const auto rest =
        test::instance_slice(nodes, test::first_elements(*sim, Output::node_positions), last, Output::node_positions);
    const TreeModel& model = sim->scene().models[0];
    size_t root = 0;
    while (model.nodes[root].parent >= 0) ++root;
    for (size_t n = 0; n < model.nodes.size(); ++n)
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(rest[3 * n + size_t(c)], model.nodes[n].position[c] - model.nodes[root].position[c], 1e-5);
}

// reserve_instances grows the capacity once (on the device where the backend can, else by an
// upload); additions up to the reserved count then grow nothing, and every output is bitwise
// what a simulation that never reserved gives.
TEST_P(LiveReshape, ReservedRoomTakesAdditionsWithoutUpload) {
    std::string skip;
    auto reserved = create(two_model_forest(), true, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    auto plain = create(two_model_forest(), true, skip);
    ASSERT_TRUE(reserved && plain);
    ASSERT_TRUE(reserved->step(5).ok());
    ASSERT_TRUE(plain->step(5).ok());
    const bool on_device = detail::backend_of(*reserved).capabilities().grows_on_device;
    auto growths = [&] { return full_uploads_of(*reserved) + device_growths_of(*reserved); };
    const uint64_t room = reserved->instance_count() + 12;
    ASSERT_TRUE(reserved->reserve_instances(room).ok());
    EXPECT_EQ(growths(), 1u);
    EXPECT_EQ(full_uploads_of(*reserved), on_device ? 0u : 1u);
    EXPECT_GE(scene_data_of(*reserved).instance_capacity, room);
    ASSERT_TRUE(reserved->reserve_instances(4).ok());
    EXPECT_EQ(growths(), 1u) << "the room is there already";
    EXPECT_EQ(test::every_output(*reserved), test::every_output(*plain));
    for (uint32_t k = 0; k < 12; ++k) {
        const Instance one[] = {{k % 2, {20.0 + 4.0 * k, 0, 0}, 0.1 * k}};
        ASSERT_TRUE(reserved->add_instances(one).ok());
        ASSERT_TRUE(plain->add_instances(one).ok());
        if (k == 5) {
            const uint64_t gone[] = {2};
            ASSERT_TRUE(reserved->remove_instances(gone).ok());
            ASSERT_TRUE(plain->remove_instances(gone).ok());
        }
    }
    EXPECT_EQ(growths(), 1u) << "every addition fitted the reserved room";
    ASSERT_TRUE(reserved->step(10).ok());
    ASSERT_TRUE(plain->step(10).ok());
    EXPECT_EQ(test::every_output(*reserved), test::every_output(*plain));
    const Status too_many = reserved->reserve_instances(uint64_t(kMaxInstances) + 1);
    EXPECT_EQ(too_many.code(), ErrorCode::unsupported);
    EXPECT_EQ(growths(), 1u);
}

std::vector<InstanceId> handles(std::initializer_list<uint64_t> values) {
    std::vector<InstanceId> out;
    for (uint64_t v : values) out.push_back(InstanceId(v));
    return out;
}

/// Swap removals between steps: two holes filled from the end, two additions, the first
/// instance's hole filled by the last added one.
void churn_by_swaps(Simulation& sim) {
    ASSERT_TRUE(sim.step(20).ok());
    ASSERT_TRUE(sim.swap_remove_instances(handles({2, 5})).ok());
    ASSERT_TRUE(sim.step(10).ok());
    const Instance added[] = {{0, {14, 0, 3}, 0.3}, {0, {-8, 0, -6}, 1.1, 0.8, 0.2}};
    ASSERT_TRUE(sim.add_instances(added).ok());
    ASSERT_TRUE(sim.swap_remove_instances(handles({0})).ok());
    ASSERT_TRUE(sim.step(15).ok());
}

// A swap removal moves only the instances that fill the holes, on the device and bit for bit;
// the others keep index and outputs, and the handles follow the moved ones.
TEST_P(LiveReshape, SwapRemovalMovesOnlyTheFillers) {
    std::string skip;
    auto sim = create(*grid_scene(test::small_tree(), 10, 5.0, 4), true, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(sim);
    ASSERT_TRUE(sim->step(25).ok());
    const auto before = test::outputs_by_instance(*sim);
    ASSERT_TRUE(sim->swap_remove_instances(handles({5, 2})).ok());
    EXPECT_EQ(full_uploads_of(*sim), 0u);
    EXPECT_EQ(scene_data_of(*sim).groups.size(), 1u) << "one model: still one run of instances";
    const size_t from[] = {0, 1, 8, 3, 4, 9, 6, 7};  // holes 2 and 5 take 8 and 9
    ASSERT_EQ(sim->instance_count(), std::size(from));
    const auto after = test::outputs_by_instance(*sim);
    for (size_t k = 0; k < std::size(from); ++k)
        for (size_t o = 0; o < std::size(test::kEveryOutput); ++o)
            EXPECT_EQ(after[k][o], before[from[k]][o]) << "output " << o << ", new index " << k;
    for (size_t k = 0; k < std::size(from); ++k) {
        EXPECT_EQ(sim->id_of(k).value(), InstanceId(from[k]));
        EXPECT_EQ(sim->index_of(InstanceId(from[k])).value(), k);
    }
    EXPECT_FALSE(sim->index_of(InstanceId(5)).ok());
    // Refused: a removed id, an unknown one, a repeat, everyone; nothing changes.
    for (const auto& bad : {handles({1, 5}), handles({77}), handles({3, 3}), handles({0, 1, 3, 4, 6, 7, 8, 9})}) {
        const Status refused = sim->swap_remove_instances(bad);
        EXPECT_EQ(refused.code(), ErrorCode::invalid_argument) << refused.message();
        EXPECT_EQ(test::outputs_by_instance(*sim), after);
        EXPECT_EQ(sim->instance_count(), std::size(from));
    }
    EXPECT_NE(sim->swap_remove_instances(handles({1, 5})).message().find("instance id 5 was removed"),
              std::string::npos);
}

// Swap removals in place give bitwise what uploading anew gives, also where a filler's model
// differs from its hole's, and follow cpu64.
TEST_P(LiveReshape, SwapRemovalEqualsUploadingAnewAndFollowsCpu64) {
    const Scene scenes[] = {*grid_scene(test::small_tree(), 10, 5.0, 4), two_model_forest()};
    for (size_t which = 0; which < std::size(scenes); ++which) {
        SCOPED_TRACE(which == 0 ? "one model" : "two models");
        std::string skip;
        auto in_place = create(scenes[which], true, skip);
        if (!skip.empty()) GTEST_SKIP() << skip;
        auto anew = create(scenes[which], false, skip);
        auto oracle = test::create_simulation_or_skip(scenes[which], test::windy_config(), BackendKind::cpu64, skip);
        ASSERT_TRUE(in_place && anew && oracle);
        for (Simulation* sim : {in_place.get(), anew.get(), oracle.get()}) churn_by_swaps(*sim);
        EXPECT_EQ(test::every_output(*in_place), test::every_output(*anew));
        // Two models: hole 5 takes the deep tree, the instance after it shifts (in place when it
        // shifts down, through an upload when up).
        if (which == 0) EXPECT_EQ(full_uploads_of(*in_place), 0u);
        EXPECT_LE(full_uploads_of(*in_place), 1u);
        const std::vector<InstanceId> ids(in_place->instance_ids().begin(), in_place->instance_ids().end());
        EXPECT_EQ(ids, std::vector<InstanceId>(oracle->instance_ids().begin(), oracle->instance_ids().end()));
        std::vector<float> nodes, expected;
        ASSERT_TRUE(in_place->read(Output::node_positions, nodes).ok());
        ASSERT_TRUE(oracle->read(Output::node_positions, expected).ok());
        ASSERT_EQ(nodes.size(), expected.size());
        const std::vector<double> a(nodes.begin(), nodes.end()), b(expected.begin(), expected.end());
        ASSERT_TRUE(test::all_finite(a));
        EXPECT_LE(test::max_abs_difference(a, b), 1e-3) << "against cpu64";
    }
}

INSTANTIATE_TEST_SUITE_P(Backends, LiveReshape,
                         ::testing::Values(BackendKind::cpu64, BackendKind::cpu, BackendKind::cpu_parallel,
                                           BackendKind::vulkan, BackendKind::cuda),
                         test::BackendTestName());

}  // namespace
}  // namespace hmsm
