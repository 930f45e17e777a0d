// Batched runs (src/vulkan/recorder.h, run_table.h): a forest of many instance groups, its
// instances alternating between models and levels of detail, runs each run of dispatches of one
// pass over its groups as one launch whose workgroups find their constants in the run table.
// The results must be those of every dispatch recorded alone, bit for bit, in every
// composition, with paused instances, split into several launches, in a scene bound in windows
// and through record_steps with frames in flight; and agree with cpu64.
#include "engine_device.h"
#include "simulation_access.h"
#include "test_compositions.h"
#include "test_trees.h"
#include "vulkan_test_support.h"

#include "vulkan/run_table.h"
#include "vulkan/windows.h"

#include <hmsm/vulkan.h>

#include <algorithm>
#include <cstdlib>
#include <optional>

namespace hmsm::test {
namespace {

constexpr int32_t kBudgets[] = {6, 3, 1};

/// Three models (a small tree, a deep one, a broom of 70 chains whose in-dispatch rounds take
/// workgroups of 128 where the others take 64), the first two with levels of detail; instances
/// in runs of one to three of a model, a few paused: dozens of instance groups, none of a
/// multiple of the workgroup size.
Scene many_groups_scene(uint32_t instances = 45) {
    Scene scene;
    scene.models = {small_tree(), deep_tree(4), broom(70)};
    scene.model_names = {"small", "deep", "broom"};
    scene.lod_budgets = {{std::begin(kBudgets), std::end(kBudgets)}, {std::begin(kBudgets), std::end(kBudgets)}};
    for (uint32_t i = 0; i < instances; ++i) {
        Instance instance;
        instance.model = (i / (1 + i % 3)) % 3;
        instance.origin = {5.0 * double(i % 9), 0.0, 5.0 * double(i / 9)};
        instance.yaw = 0.37 * double(i);
        instance.wind_scale = 0.8 + 0.05 * double(i % 7);
        instance.active = i % 11 != 4;
        scene.instances.push_back(instance);
    }
    return scene;
}

/// Switches the instances of the first two models of `scene` (the brooms have no levels) to
/// their levels of detail by index, so that levels alternate within runs of one model.
void switch_levels(Simulation& sim, const Scene& scene, uint32_t shift) {
    std::vector<InstanceId> ids;
    std::vector<uint32_t> levels;
    for (uint32_t i = 0; i < sim.instance_count(); ++i) {
        if (scene.instances[i].model == 2) continue;
        ids.push_back(*sim.id_of(i));
        levels.push_back((i + shift) % 4);
    }
    const Status status = sim.set_instance_lods(ids, levels);
    ASSERT_TRUE(status.ok()) << status.message();
}

const detail::vk::VulkanBackend& vulkan_of(const Simulation& sim) {
    return dynamic_cast<const detail::vk::VulkanBackend&>(detail::backend_of(sim));
}

/// Backends created in its scope batch runs as asked (and split launches past
/// `max_workgroups`).
class BatchRuns {
public:
    explicit BatchRuns(bool enabled, uint64_t max_workgroups = 0) {
        detail::vulkan_set_batch_runs(enabled, max_workgroups);
    }
    ~BatchRuns() { detail::vulkan_set_batch_runs(std::nullopt); }
};

std::unique_ptr<Simulation> create(const Scene& scene, TestComposition composition, BackendKind kind,
                                   std::string& skip) {
    SimulationConfig config = windy_config();
    config.composition = composition.composition;
    return create_simulation_or_skip(scene, config, kind, skip, composition.jumping_form);
}

/// The same changes and steps on each simulation: levels switched, steps, an instance paused
/// and another resumed, levels switched again (the program changes), steps.
void drive(Simulation& sim, const Scene& scene) {
    switch_levels(sim, scene, 0);
    if (testing::Test::HasFatalFailure()) return;
    ASSERT_TRUE(sim.step(3).ok());
    ASSERT_TRUE(sim.set_instance_active(7, false).ok());
    ASSERT_TRUE(sim.set_instance_active(4, true).ok());
    ASSERT_TRUE(sim.step(2).ok());
    switch_levels(sim, scene, 1);
    if (testing::Test::HasFatalFailure()) return;
    ASSERT_TRUE(sim.step(3).ok());
}

class BatchedRuns : public VulkanTest, public ::testing::WithParamInterface<TestComposition> {
protected:
    std::unique_ptr<Simulation> make(const Scene& scene, bool batched, uint64_t max_workgroups = 0) {
        SimulationConfig config = windy_config();
        config.composition = GetParam().composition;
        std::string skip;
        std::unique_ptr<Simulation> sim;
        {
            BatchRuns batching(batched, max_workgroups);
            sim = create_simulation_or_skip(scene, config, BackendKind::vulkan, skip, GetParam().jumping_form);
        }
        if (!skip.empty()) skip_ = skip;
        return sim;
    }
    std::string skip_;
};

TEST_P(BatchedRuns, MatchEveryDispatchAloneBitForBitAndAgreeWithCpu64) {
    const Scene scene = many_groups_scene();
    auto off = make(scene, false);
    if (!skip_.empty()) GTEST_SKIP() << skip_;
    auto on = make(scene, true);
    auto split = make(scene, true, 3);  // launches of at most 3 workgroups: most runs split
    SimulationConfig exact = windy_config();
    exact.composition = GetParam().composition;
    exact.backend = BackendKind::cpu64;
    auto oracle = create_simulation(scene, exact, GetParam());
    ASSERT_TRUE(off && on && split && oracle.ok());
    for (Simulation* sim : {off.get(), on.get(), split.get(), oracle.value().get()}) {
        drive(*sim, scene);
        if (HasFatalFailure()) return;
    }
    EXPECT_FALSE(vulkan_of(*off).batches_runs());
    EXPECT_TRUE(vulkan_of(*on).batches_runs());
    const auto expected = every_output(*off);
    EXPECT_TRUE(same_bits(every_output(*on), expected));
    EXPECT_TRUE(same_bits(every_output(*split), expected));

    // Dozens of groups per run: the launches fall to a few per pass.
    const size_t alone = vulkan_of(*off).launches_per_step(), batched = vulkan_of(*on).launches_per_step();
    const size_t groups = detail::scene_data_of(*on).groups.size();
    EXPECT_GT(groups, 20u);
    EXPECT_GE(alone, groups);
    EXPECT_LE(batched * 5, alone) << batched << " launches batched, " << alone << " alone";
    EXPECT_GT(vulkan_of(*split).launches_per_step(), batched);

    for (Output output : {Output::node_positions, Output::vertex_positions, Output::chain_angles}) {
        std::vector<double> a, b;
        ASSERT_TRUE(on->read(output, a).ok());
        ASSERT_TRUE(oracle.value()->read(output, b).ok());
        EXPECT_LT(relative_difference(a, b), 1e-4) << "output " << int(output);
    }
}

INSTANTIATE_TEST_SUITE_P(Compositions, BatchedRuns, ::testing::ValuesIn(kEveryComposition),
                         [](const auto& info) { return name_of(info.param); });

TEST_F(VulkanTest, BatchedRunsMatchInASceneBoundInWindows) {
    const Scene scene = many_groups_scene(24);
    std::string skip;
    auto whole = create(scene, kJumpingInDispatch, BackendKind::vulkan, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(whole);
    // A few instances per window: runs of one pass are cut at the segments' edges.
    uint64_t one = 0;
    for (const detail::ModelRange& m : detail::scene_data_of(*whole).models)
        one = std::max<uint64_t>({one, m.vertex_count * 16, m.node_count * 16, 2 * m.chain_count * 48});
    std::unique_ptr<Simulation> split[2];
    for (bool batched : {false, true}) {
        BatchRuns batching(batched);
        detail::vulkan_set_window_bytes(3 * one + 1024);
        split[batched] = create(scene, kJumpingInDispatch, BackendKind::vulkan, skip);
        detail::vulkan_set_window_bytes(0);
        if (!skip.empty()) GTEST_SKIP() << skip;
        ASSERT_TRUE(split[batched]);
        EXPECT_GT(vulkan_of(*split[batched]).window_plan().segments().size(), 2u);
        ASSERT_TRUE(split[batched]->step(6).ok());
    }
    EXPECT_TRUE(same_bits(every_output(*split[1]), every_output(*split[0])));
    EXPECT_LT(vulkan_of(*split[1]).launches_per_step(), vulkan_of(*split[0]).launches_per_step());
}

TEST_F(VulkanTest, BatchedRunsTravelWithRecordedFrames) {
    std::string no_device;
    auto engine = EngineDevice::create(no_device);
    if (!no_device.empty()) GTEST_SKIP() << no_device;
    ASSERT_TRUE(engine);
    // Instances start in long runs of one model (few groups); switching levels in flight makes
    // many, so the run table grows while earlier frames still read it.
    Scene scene = many_groups_scene(40);
    for (size_t i = 0; i < scene.instances.size(); ++i) scene.instances[i].model = uint32_t(i / 16);
    for (Composition composition : {Composition::pointer_jumping, Composition::level_by_level, Composition::path_walk}) {
        SCOPED_TRACE(to_string(composition));
        SimulationConfig config = windy_config();
        config.composition = composition;
        Result<std::unique_ptr<Simulation>> recorded = Status{ErrorCode::internal, "not created"};
        {
            BatchRuns batching(true);
            recorded = vulkan::create_simulation(scene, config, engine->context());
        }
        ASSERT_TRUE(recorded.ok()) << recorded.status().message();
        EXPECT_TRUE(vulkan_of(*recorded.value()).batches_runs());
        Simulation& sim = *recorded.value();
        std::string skip;
        std::unique_ptr<Simulation> reference;
        {
            BatchRuns batching(false);
            reference = create_simulation_or_skip(scene, config, BackendKind::vulkan, skip);
        }
        ASSERT_TRUE(reference);
        const size_t groups_before = detail::scene_data_of(sim).groups.size();
        {
            EngineFrames frames(*engine, 3);
            if (HasFailure()) return;
            for (uint32_t f = 0; f < 9; ++f) {
                for (Simulation* s : {&sim, reference.get()}) {
                    if (f == 3) switch_levels(*s, scene, 0);
                    if (f == 6) switch_levels(*s, scene, 1);
                    if (f == 5) ASSERT_TRUE(s->set_instance_active(9, false).ok());
                    if (HasFatalFailure()) return;
                }
                VkCommandBuffer cmd = frames.begin(f);
                const Status status = vulkan::record_steps(sim, cmd, 2);
                frames.submit(f);
                ASSERT_TRUE(status.ok()) << "frame " << f << ": " << status.message();
                ASSERT_TRUE(reference->step(2).ok());
            }
            frames.wait_all();
        }
        EXPECT_GT(detail::scene_data_of(sim).groups.size(), 3 * groups_before);
        EXPECT_LT(vulkan_of(sim).launches_per_step(), vulkan_of(*reference).launches_per_step());
        EXPECT_TRUE(same_bits(every_output(sim), every_output(*reference)));
        recorded.value().reset();  // before the engine's device
    }
}

TEST_F(VulkanTest, BatchingFollowsTheEnvironmentElseTheDevice) {
    std::string skip;
    for (const char* value : {"0", "1", ""}) {
        if (*value) ::setenv("HMSM_VULKAN_BATCH_RUNS", value, 1);
        auto sim = create(single_tree_scene(small_tree()), Composition::pointer_jumping, BackendKind::vulkan, skip);
        ::unsetenv("HMSM_VULKAN_BATCH_RUNS");
        if (!skip.empty()) GTEST_SKIP() << skip;
        ASSERT_TRUE(sim);
        const bool expected = *value ? value[0] == '1' : !vulkan_of(*sim).device().is_cpu();
        EXPECT_EQ(vulkan_of(*sim).batches_runs(), expected) << "HMSM_VULKAN_BATCH_RUNS=" << value;
    }
}

}  // namespace
}  // namespace hmsm::test
