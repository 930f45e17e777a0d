// Growth past the capacity on the device (docs/driving.md, streaming budgets): a simulation
// that adds, switches levels and swap-removes past its capacity again and again gives bit for
// bit what one that reserved enough up front gives, and what one that grows by uploading the
// scene anew gives, under the paper's and the coupled dynamics, on every backend; it never
// uploads the scene anew, and its growths are geometric. Backend::grow keeps every live element
// (both halves of the ping-pong buffers at their new place) and zeroes the rest.
#include "test_trees.h"

#include "backend.h"
#include "capacity_growth.h"
#include "simulation_access.h"

#include <gtest/gtest.h>

#include <algorithm>

namespace hmsm {
namespace {

using detail::BufferId;
using detail::device_growths_of;
using detail::full_uploads_of;

Scene growth_scene() {
    Scene scene = test::small_and_deep_with_levels(3);
    scene.instances[2].active = false;  // a paused instance moves with the others
    return scene;
}

SimulationConfig config_of(bool coupled) {
    SimulationConfig config = test::windy_config();
    if (coupled) config.model.dynamics = Dynamics::coupled;
    return config;
}

struct GrowthCase {
    BackendKind backend;
    bool coupled;
};

class CapacityGrowth : public ::testing::TestWithParam<GrowthCase> {};

/// Every instance's handle, in list order.
std::vector<InstanceId> ids_of(const Simulation& sim) { return {sim.instance_ids().begin(), sim.instance_ids().end()}; }

/// Switches every instance to `level`.
Status switch_all(Simulation& sim, uint32_t level) {
    const std::vector<InstanceId> ids = ids_of(sim);
    const std::vector<uint32_t> levels(ids.size(), level);
    return sim.set_instance_lods(ids, levels);
}

TEST_P(CapacityGrowth, GrowingOnTheDeviceEqualsReservingAndUploading) {
    std::string skip;
    const Scene scene = growth_scene();
    auto reserved = test::create_simulation_or_skip(scene, config_of(GetParam().coupled), GetParam().backend, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    auto device = test::create_simulation_or_skip(scene, config_of(GetParam().coupled), GetParam().backend, skip);
    auto uploads = test::create_simulation_or_skip(scene, config_of(GetParam().coupled), GetParam().backend, skip);
    ASSERT_TRUE(reserved && device && uploads);
    detail::SimulationAccess::impl(*uploads).device_growth_ = false;
    ASSERT_TRUE(reserved->reserve_instances(80).ok());
    EXPECT_EQ(full_uploads_of(*reserved), 0u) << "the reserve grows on the device";
    EXPECT_EQ(device_growths_of(*reserved), 1u);
    Simulation* sims[] = {reserved.get(), device.get(), uploads.get()};
    auto all = [&](auto&& change) {
        for (Simulation* sim : sims) ASSERT_TRUE(change(*sim).ok());
    };
    auto expect_same = [&](const std::string& when) {
        const auto expected = test::every_output(*reserved);
        EXPECT_TRUE(test::same_bits(test::every_output(*device), expected)) << "grown on the device, " << when;
        EXPECT_TRUE(test::same_bits(test::every_output(*uploads), expected)) << "grown by uploads, " << when;
        EXPECT_EQ(ids_of(*device), ids_of(*reserved)) << when;
        EXPECT_EQ(ids_of(*uploads), ids_of(*reserved)) << when;
    };
    all([](Simulation& s) { return s.step(20); });
    all([](Simulation& s) { return switch_all(s, 2); });  // coarse: room for more instances
    uint64_t grown_by_adds = 0, grown_by_switches = 0;
    for (uint32_t round = 0; round < 5; ++round) {
        const std::string when = "round " + std::to_string(round);
        // Adds at the full level, which then turn coarse.
        std::vector<Instance> added;
        for (uint32_t k = 0; k < 4 + round; ++k)
            added.push_back({(round + k) % 2, {-20.0 + 3.0 * k, 0.0, 6.0 * round}, 0.3 * k, 0.8 + 0.1 * k, 0.1 * round});
        uint64_t before = device_growths_of(*device);
        all([&](Simulation& s) { return s.add_instances(added); });
        grown_by_adds += device_growths_of(*device) - before;
        all([](Simulation& s) { return s.step(7); });
        expect_same("after the adds of " + when);
        std::vector<InstanceId> fresh(device->instance_ids().end() - std::ptrdiff_t(added.size()),
                                      device->instance_ids().end());
        all([&](Simulation& s) { return s.set_instance_lods(fresh, std::vector<uint32_t>(fresh.size(), 2)); });
        // Every instance to its finest level: more chains, nodes and vertices than the room.
        before = device_growths_of(*device);
        all([](Simulation& s) { return switch_all(s, 0); });
        grown_by_switches += device_growths_of(*device) - before;
        all([](Simulation& s) { return s.step(5); });
        expect_same("after the switch to the finest level, " + when);
        // Back to coarse for some, swap removals and an ordered removal.
        const std::vector<InstanceId> ids = ids_of(*device);
        const InstanceId coarse[] = {ids[1], ids[ids.size() - 2], ids[ids.size() / 2]};
        const uint32_t levels[] = {3, 1, 2};
        all([&](Simulation& s) { return s.set_instance_lods(coarse, levels); });
        const InstanceId leaving[] = {ids[round], ids[ids.size() - 3]};
        all([&](Simulation& s) { return s.swap_remove_instances(leaving); });
        const uint64_t gone[] = {2};
        all([&](Simulation& s) { return s.remove_instances(gone); });
        all([](Simulation& s) { return s.step(6); });
        expect_same("after the removals of " + when);
        all([](Simulation& s) { return switch_all(s, 2); });
        if (testing::Test::HasFailure()) return;
    }
    EXPECT_EQ(full_uploads_of(*device), 0u) << "growth took the device path";
    EXPECT_EQ(device_growths_of(*uploads), 0u);
    EXPECT_GE(full_uploads_of(*uploads), 3u) << "the comparison grew by uploads";
    EXPECT_GE(grown_by_adds, 1u) << "adds grew the capacity";
    EXPECT_GE(grown_by_switches, 1u) << "level switches grew the capacity";
    // Geometric: the capacities grow 1.5 times at a time, from 10 trees to a few times that.
    EXPECT_GE(device_growths_of(*device), 3u);
    EXPECT_LE(device_growths_of(*device), 16u) << "growth is amortized";
    EXPECT_EQ(full_uploads_of(*reserved), 0u);
    EXPECT_EQ(device_growths_of(*reserved), 1u) << "every change fitted the reserve";
}

std::string case_name(const ::testing::TestParamInfo<GrowthCase>& info) {
    return test::backend_test_name(info.param.backend) + (info.param.coupled ? "_coupled" : "_paper");
}

INSTANTIATE_TEST_SUITE_P(Backends, CapacityGrowth,
                         ::testing::Values(GrowthCase{BackendKind::cpu64, false}, GrowthCase{BackendKind::cpu64, true},
                                           GrowthCase{BackendKind::cpu, false}, GrowthCase{BackendKind::cpu, true},
                                           GrowthCase{BackendKind::cpu_parallel, false},
                                           GrowthCase{BackendKind::cpu_parallel, true},
                                           GrowthCase{BackendKind::vulkan, false}, GrowthCase{BackendKind::vulkan, true},
                                           GrowthCase{BackendKind::cuda, false}, GrowthCase{BackendKind::cuda, true}),
                         case_name);

// The plan of one buffer's growth: a ping-pong buffer's second half moves to the new capacity.
TEST(CapacityGrowthPlan, SecondHalfMovesToTheNewCapacity) {
    const detail::GrowthPlan halves = detail::growth_plan(BufferId::chain_rotation, 20, 30, 7);
    ASSERT_TRUE(halves.reallocates);
    ASSERT_EQ(halves.copies.size(), 2u);
    EXPECT_TRUE(halves.copies[0].src == 0 && halves.copies[0].dst == 0 && halves.copies[0].count == 7);
    EXPECT_TRUE(halves.copies[1].src == 10 && halves.copies[1].dst == 15 && halves.copies[1].count == 7);
    ASSERT_EQ(halves.zeros.size(), 2u);
    EXPECT_TRUE(halves.zeros[0].first == 7 && halves.zeros[0].count == 8);
    EXPECT_TRUE(halves.zeros[1].first == 22 && halves.zeros[1].count == 8);
    const detail::GrowthPlan one = detail::growth_plan(BufferId::node_world, 12, 18, 12);
    ASSERT_EQ(one.copies.size(), 1u);
    EXPECT_EQ(one.copies[0].count, 12u);
    ASSERT_EQ(one.zeros.size(), 1u);
    EXPECT_TRUE(one.zeros[0].first == 12 && one.zeros[0].count == 6);
    EXPECT_FALSE(detail::growth_plan(BufferId::chain_constants, 5, 5, 5).reallocates) << "model scope stays";
    EXPECT_FALSE(detail::growth_plan(BufferId::chain_state, 9, 9, 9).reallocates) << "same size: nothing to do";
    EXPECT_EQ(detail::grown_capacity(100, 101, 1000), 150u);
    EXPECT_EQ(detail::grown_capacity(100, 400, 1000), 400u);
    EXPECT_EQ(detail::grown_capacity(100, 90, 1000), 100u);
}

class BackendGrowth : public ::testing::TestWithParam<BackendKind> {};

/// A value per scalar that tells buffer, element and scalar apart, exact in float.
double marker(BufferId id, uint64_t element, uint32_t scalar) {
    return double(uint32_t(id) + 1) * 1000.0 + double(element % 4096) + double(scalar) / 64.0;
}

// Backend::grow keeps each capacity-sized buffer's live elements (both halves of a ping-pong
// buffer, the second at the new chain capacity), zeroes the rest and leaves model buffers be.
TEST_P(BackendGrowth, KeepsLiveElementsAndMovesTheSecondHalf) {
    std::string skip;
    SimulationConfig config = test::windy_config();
    config.model.dynamics = Dynamics::coupled;  // chain_load: a third ping-pong buffer
    auto sim = test::create_simulation_or_skip(growth_scene(), config, GetParam(), skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(sim);
    detail::Backend& backend = detail::backend_of(*sim);
    ASSERT_TRUE(backend.capabilities().grows_on_device);
    const detail::SceneData& live = detail::scene_data_of(*sim);
    detail::SceneData grown = live;
    grown.chain_capacity = live.chain_capacity * 2 + 3;
    grown.node_capacity = live.node_capacity + live.node_capacity / 2;
    grown.vertex_capacity = live.vertex_capacity + 5;
    grown.instance_capacity = live.instance_capacity + 7;
    const detail::Scalar as = detail::Scalar::f64;
    auto scalars = [](BufferId id) { return detail::shape_scalars(detail::buffer_info(id).shape); };
    const uint64_t model_chains = live.element_count(BufferId::chain_constants);
    std::vector<double> model_before(model_chains * 4);
    ASSERT_TRUE(backend.read(BufferId::chain_constants, 0, model_chains, model_before.data(), as).ok());
    // Markers written, then read back as the backend stores them (a CPU matrix keeps no fourth
    // row): what the live elements must hold after the growth.
    std::vector<std::vector<double>> stored(detail::kBufferCount);
    for (const detail::BufferInfo& info : detail::kBufferTable) {
        if (!detail::sized_by_capacity(info.id) || live.element_count(info.id) == 0) continue;
        const uint64_t n = detail::live_elements(live, info.id), half = live.element_count(info.id) / detail::halves_of(info.id);
        for (uint32_t h = 0; h < detail::halves_of(info.id); ++h) {
            std::vector<double> values(n * scalars(info.id));
            for (uint64_t e = 0; e < n; ++e)
                for (uint32_t k = 0; k < scalars(info.id); ++k) values[e * scalars(info.id) + k] = marker(info.id, e + h * 7, k);
            ASSERT_TRUE(backend.write(info.id, h * half, n, values.data(), as).ok()) << info.name;
            ASSERT_TRUE(backend.read(info.id, h * half, n, values.data(), as).ok()) << info.name;
            if (n > 0) EXPECT_EQ(values[0], marker(info.id, h * 7, 0)) << info.name << ": the marker is stored";
            stored[uint32_t(info.id)].insert(stored[uint32_t(info.id)].end(), values.begin(), values.end());
        }
    }
    ASSERT_TRUE(backend.grow(grown).ok());
    for (const detail::BufferInfo& info : detail::kBufferTable) {
        if (!detail::sized_by_capacity(info.id) || grown.element_count(info.id) == 0) continue;
        SCOPED_TRACE(std::string(info.name));
        const uint64_t n = detail::live_elements(live, info.id), half = grown.element_count(info.id) / detail::halves_of(info.id);
        for (uint32_t h = 0; h < detail::halves_of(info.id); ++h) {
            std::vector<double> values(half * scalars(info.id));
            ASSERT_TRUE(backend.read(info.id, h * half, half, values.data(), as).ok());
            bool kept = true, zeroed = true;
            for (uint64_t e = 0; e < half; ++e)
                for (uint32_t k = 0; k < scalars(info.id); ++k) {
                    const double v = values[e * scalars(info.id) + k];
                    if (e < n) kept = kept && v == stored[uint32_t(info.id)][(h * n + e) * scalars(info.id) + k];
                    else zeroed = zeroed && v == 0.0;
                }
            EXPECT_TRUE(kept) << "half " << h << ": the live elements are kept";
            EXPECT_TRUE(zeroed) << "half " << h << ": the elements past them are zero";
        }
    }
    std::vector<double> model_after(model_before.size());
    ASSERT_TRUE(backend.read(BufferId::chain_constants, 0, model_chains, model_after.data(), as).ok());
    EXPECT_EQ(model_after, model_before) << "model buffers stay";
}

INSTANTIATE_TEST_SUITE_P(Backends, BackendGrowth,
                         ::testing::Values(BackendKind::cpu64, BackendKind::cpu, BackendKind::cpu_parallel,
                                           BackendKind::vulkan, BackendKind::cuda),
                         test::BackendTestName());

}  // namespace
}  // namespace hmsm
