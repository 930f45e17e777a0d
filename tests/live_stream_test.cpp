// Streaming (docs/driving.md, streaming budgets): a long random sequence of adds, swap
// removals, level switches (by distance bands and by handle), pauses and steps gives bit for
// bit the outputs, instance lists, handles and groups of the same sequence taken through the
// general paths (reshape, a switch laid out anew, update_lod examining every instance), on
// every backend, within a reserved capacity and growing past it.
#include "test_trees.h"

#include "lod_tracker.h"
#include "simulation_access.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <random>

namespace hmsm {
namespace {

Scene stream_scene() { return test::small_and_deep_with_levels(4); }

Instance random_instance(std::mt19937& rng) {
    std::uniform_real_distribution<double> place(-30.0, 30.0), unit(0.0, 1.0);
    Instance t;
    t.model = rng() % 2;
    t.origin = {place(rng), 0.0, place(rng)};
    t.yaw = 6.0 * unit(rng);
    t.wind_scale = 0.5 + unit(rng);
    t.wind_phase = unit(rng);
    t.active = rng() % 7 != 0;
    return t;
}

/// Every output the simulation produces, as doubles.
std::vector<std::vector<double>> outputs_of(const Simulation& sim) {
    std::vector<std::vector<double>> all;
    for (Output output : test::kEveryOutput) {
        std::vector<double> values;
        const Status read = sim.read(output, values);
        EXPECT_TRUE(read.ok()) << read.message();
        all.push_back(std::move(values));
    }
    return all;
}

/// The lists, totals and (in the packed layout; the placed one keeps none) groups of both.
void expect_same_lists(const Simulation& fast, const Simulation& slow, int frame) {
    ASSERT_EQ(fast.instance_count(), slow.instance_count()) << "frame " << frame;
    for (uint64_t i = 0; i < fast.instance_count(); ++i) {
        EXPECT_EQ(fast.instance_ids()[i], slow.instance_ids()[i]) << "frame " << frame << ", instance " << i;
        EXPECT_EQ(fast.instances()[i].model, slow.instances()[i].model) << "frame " << frame << ", instance " << i;
        EXPECT_EQ(fast.instances()[i].origin, slow.instances()[i].origin) << "frame " << frame;
        EXPECT_EQ(*fast.index_of(fast.instance_ids()[i]), i) << "frame " << frame;
    }
    const detail::SceneData& a = detail::scene_data_of(fast);
    const detail::SceneData& b = detail::scene_data_of(slow);
    EXPECT_EQ(a.total_chains, b.total_chains) << "frame " << frame;
    EXPECT_EQ(a.total_nodes, b.total_nodes) << "frame " << frame;
    EXPECT_EQ(a.total_vertices, b.total_vertices) << "frame " << frame;
    if (fast.config().instance_layout == InstanceLayout::placed && a.groups.empty()) return;
    ASSERT_EQ(a.groups.size(), b.groups.size()) << "frame " << frame;
    for (size_t g = 0; g < a.groups.size(); ++g) {
        const detail::InstanceGroup &x = a.groups[g], &y = b.groups[g];
        EXPECT_TRUE(x.model == y.model && x.instance_begin == y.instance_begin && x.instance_count == y.instance_count &&
                    x.chain_begin == y.chain_begin && x.node_begin == y.node_begin && x.vertex_begin == y.vertex_begin)
            << "frame " << frame << ", group " << g;
    }
}

// update_lod's queue hands over exactly the entries whose key the travel reached, each once,
// whatever the spread of the keys (the next call's, far ones, none).
TEST(TravelQueue, TakesEveryEntryOnceItsTravelCame) {
    detail::TravelQueue queue;
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> spread(0.0, 400.0);
    std::vector<double> keys;
    for (uint64_t id = 0; id < 2000; ++id) {
        const double key = id % 97 == 0   ? -std::numeric_limits<double>::infinity()
                           : id % 89 == 0 ? std::numeric_limits<double>::infinity()
                                          : spread(rng);
        keys.push_back(key);
        queue.push({key, uint32_t(id)});
    }
    std::vector<int> taken(keys.size(), 0);
    for (double t = -1.0; t <= 450.0; t += 0.37) {
        queue.take_until(t, [&](const detail::TravelEntry& e) {
            ++taken[e.index];
            EXPECT_LE(e.key, t);
        });
        for (size_t id = 0; id < keys.size(); ++id)
            ASSERT_EQ(taken[id], keys[id] <= t ? 1 : 0) << "id " << id << " at travel " << t;
    }
    EXPECT_EQ(queue.size(), 0u) << "only the +infinity keys were never kept";
}

// The same with keys far past the queue's ring of buckets, entries pushed while the travel
// goes on (each at a key not below it), jumps of the travel past the whole ring, and a clear()
// after which the travel starts again from zero.
TEST(TravelQueue, TakesFarKeysAndLatePushesOnceEach) {
    std::mt19937 rng(7);
    for (int round = 0; round < 2; ++round) {
        detail::TravelQueue queue;
        if (round == 1) {  // a queue used far ahead, then cleared
            queue.push({50000.0, 0});
            queue.take_until(60000.0, [](const detail::TravelEntry&) {});
            queue.clear();
        }
        std::vector<double> keys;
        std::vector<int> taken;
        auto push = [&](double key) {
            keys.push_back(key);
            taken.push_back(0);
            queue.push({key, uint32_t(keys.size() - 1)});
        };
        std::uniform_real_distribution<double> far(0.0, 30000.0);
        for (int k = 0; k < 3000; ++k) push(k % 101 == 0 ? -std::numeric_limits<double>::infinity() : far(rng));
        double t = -1.0;
        while (t < 31000.0) {
            t += rng() % 50 == 0 ? 5000.0 : 13.7;  // now and then past the whole ring
            queue.take_until(t, [&](const detail::TravelEntry& e) {
                ++taken[e.index];
                EXPECT_LE(e.key, t);
            });
            for (size_t i = 0; i < keys.size(); ++i)
                ASSERT_EQ(taken[i], keys[i] <= t ? 1 : 0) << "entry " << i << " at travel " << t << ", round " << round;
            for (int k = 0; k < 5; ++k) push(t + std::uniform_real_distribution<double>(0.0, 9000.0)(rng));
        }
        queue.take_until(1e9, [&](const detail::TravelEntry& e) { ++taken[e.index]; });
        EXPECT_EQ(queue.size(), 0u);
        for (size_t i = 0; i < keys.size(); ++i) EXPECT_EQ(taken[i], 1) << "entry " << i;
    }
}

struct StreamCase {
    BackendKind backend;
    bool reserved;  // room reserved up front (in place throughout) or grown on the way
    InstanceLayout layout = InstanceLayout::packed;  // of the streaming side
};

class Streaming : public ::testing::TestWithParam<StreamCase> {};

TEST_P(Streaming, RandomSequenceMatchesGeneralPaths) {
    std::string skip;
    SimulationConfig streaming = test::windy_config();
    streaming.instance_layout = GetParam().layout;
    auto fast = test::create_simulation_or_skip(stream_scene(), streaming, GetParam().backend, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    auto slow = test::create_simulation_or_skip(stream_scene(), test::windy_config(), GetParam().backend, skip);
    ASSERT_TRUE(fast && slow);
    auto& general = detail::SimulationAccess::impl(*slow);
    general.streaming_paths_ = false;
    LodBands bands;
    bands.edges = {8.0, 16.0, 24.0};
    bands.hysteresis = 0.1;
    ASSERT_TRUE(fast->set_lod_bands(bands).ok());
    ASSERT_TRUE(slow->set_lod_bands(bands).ok());
    if (GetParam().reserved) {
        ASSERT_TRUE(fast->reserve_instances(200).ok());
        ASSERT_TRUE(slow->reserve_instances(200).ok());
    }
    const uint64_t uploads_before = detail::full_uploads_of(*fast);

    std::mt19937 rng(20261127);
    Vec3 viewer{0.0};
    std::uniform_real_distribution<double> stride(-3.0, 3.0);
    uint64_t switched = 0, removed = 0, added = 0;
    for (int frame = 0; frame < 70; ++frame) {
        // Swap removals: up to five random handles, never every instance.
        const std::vector<InstanceId> live(fast->instance_ids().begin(), fast->instance_ids().end());
        std::vector<InstanceId> leaving;
        const size_t remove_count = std::min<size_t>(rng() % 6, live.size() - 1);
        std::sample(live.begin(), live.end(), std::back_inserter(leaving), remove_count, rng);
        std::shuffle(leaving.begin(), leaving.end(), rng);
        ASSERT_TRUE(fast->swap_remove_instances(leaving).ok()) << "frame " << frame;
        ASSERT_TRUE(slow->swap_remove_instances(leaving).ok()) << "frame " << frame;
        removed += leaving.size();
        // Adds.
        std::vector<Instance> coming;
        for (size_t k = rng() % 6; k > 0; --k) coming.push_back(random_instance(rng));
        ASSERT_TRUE(fast->add_instances(coming).ok()) << "frame " << frame;
        ASSERT_TRUE(slow->add_instances(coming).ok()) << "frame " << frame;
        added += coming.size();
        // A pause or resume now and then.
        if (rng() % 3 == 0) {
            const uint64_t i = rng() % fast->instance_count();
            const bool active = rng() % 2 == 0;
            ASSERT_TRUE(fast->set_instance_active(i, active).ok());
            ASSERT_TRUE(slow->set_instance_active(i, active).ok());
        }
        // Switches by handle now and then.
        if (rng() % 4 == 0) {
            const InstanceId id = fast->instance_ids()[rng() % fast->instance_count()];
            const uint32_t level = rng() % 4;
            ASSERT_TRUE(fast->set_instance_lod(id, level).ok());
            ASSERT_TRUE(slow->set_instance_lod(id, level).ok());
        }
        // The viewer walks, and jumps now and then; the general side examines every instance.
        viewer += Vec3(stride(rng), 0.0, stride(rng));
        if (rng() % 10 == 0) viewer = Vec3(stride(rng) * 8.0, 0.0, stride(rng) * 8.0);
        general.lod_tracker_.invalidate();
        const Result<uint64_t> a = fast->update_lod(viewer), b = slow->update_lod(viewer);
        ASSERT_TRUE(a.ok() && b.ok()) << "frame " << frame;
        EXPECT_EQ(*a, *b) << "frame " << frame;
        switched += *a;
        ASSERT_TRUE(fast->step(1).ok());
        ASSERT_TRUE(slow->step(1).ok());
        expect_same_lists(*fast, *slow, frame);
        EXPECT_TRUE(test::same_bits(outputs_of(*fast), outputs_of(*slow))) << "frame " << frame;
        if (testing::Test::HasFailure()) return;
    }
    EXPECT_GT(switched, 20u) << "the bands switch instances on the way";
    EXPECT_GT(removed, 50u);
    EXPECT_GT(added, 50u);
    if (GetParam().reserved)
        EXPECT_EQ(detail::full_uploads_of(*fast), uploads_before) << "within the reserve every change stays in place";
    else
        // Growth is geometric: each of the four capacities (instances, chains, nodes,
        // vertices) grows 1.5 times at a time from the 17 trees of the scene to a few times
        // that, a handful of uploads each.
        EXPECT_LE(detail::full_uploads_of(*fast) - uploads_before, 30u) << "growth is amortized";
}

std::string case_name(const ::testing::TestParamInfo<StreamCase>& info) {
    std::string name = std::string(to_string(info.param.backend)) + (info.param.reserved ? "_reserved" : "_growing") +
                       (info.param.layout == InstanceLayout::placed ? "_placed" : "");
    std::replace(name.begin(), name.end(), '-', '_');
    return name;
}

INSTANTIATE_TEST_SUITE_P(Backends, Streaming,
                         ::testing::Values(StreamCase{BackendKind::cpu64, true}, StreamCase{BackendKind::cpu64, false},
                                           StreamCase{BackendKind::cpu, true}, StreamCase{BackendKind::cpu, false},
                                           StreamCase{BackendKind::cpu_parallel, true},
                                           StreamCase{BackendKind::vulkan, true},
                                           StreamCase{BackendKind::vulkan, false},
                                           StreamCase{BackendKind::cuda, true},
                                           StreamCase{BackendKind::cpu64, true, InstanceLayout::placed},
                                           StreamCase{BackendKind::vulkan, true, InstanceLayout::placed},
                                           StreamCase{BackendKind::vulkan, false, InstanceLayout::placed},
                                           StreamCase{BackendKind::cuda, true, InstanceLayout::placed},
                                           StreamCase{BackendKind::cuda, false, InstanceLayout::placed}),
                         case_name);

}  // namespace
}  // namespace hmsm
