// Recorded steps replayed from secondary command buffers (src/vulkan/step_replay.h): each
// record_steps executes a secondary that holds the step program's commands, recorded again only
// when the program changes. Frames whose live data changes (gusts, a turned wind, a moving force
// field, step counts that shift the load halves of the coupled dynamics) and frames that reset
// a tree (a one-off program) replay the same secondaries; adding a tree, switching levels,
// starting and ending fades record new ones. The
// results must equal the same frames stepped with step(), under synchronization validation.
#include "engine_device.h"
#include "simulation_access.h"
#include "test_trees.h"
#include "vulkan_test_support.h"

#include "vulkan/step_replay.h"

#include <hmsm/vulkan.h>

namespace hmsm::test {
namespace {

class StepReplay : public VulkanTest, public ::testing::WithParamInterface<Dynamics> {
protected:
    void SetUp() override {
        VulkanTest::SetUp();
        detail::vulkan_set_step_replay(true);
    }
    void TearDown() override {
        detail::vulkan_set_step_replay(std::nullopt);
        VulkanTest::TearDown();
    }
};

const detail::vk::VulkanBackend& vulkan_of(const Simulation& s) {
    return dynamic_cast<const detail::vk::VulkanBackend&>(detail::backend_of(s));
}

void expect_same_outputs(const Simulation& sim, const Simulation& reference) {
    EXPECT_EQ(sim.steps_done(), reference.steps_done());
    ASSERT_EQ(sim.instance_count(), reference.instance_count());
    for (size_t i = 0; i < sim.instance_count(); ++i) EXPECT_EQ(sim.instances()[i].model, reference.instances()[i].model);
    for (Output output : {Output::node_positions, Output::vertex_positions, Output::joint_matrices}) {
        std::vector<float> a, b;
        ASSERT_TRUE(sim.read(output, a).ok());
        ASSERT_TRUE(reference.read(output, b).ok());
        EXPECT_EQ(a, b) << "output " << int(output);
    }
}

void gust(Simulation& s, uint32_t f) {
    Wind wind = s.wind();
    wind.strength = 6.0 + 0.5 * double(f % 5);
    if (f == 4) wind.direction = {0.8, 0.0, 0.6};  // rewrites every instance's wind data
    ASSERT_TRUE(s.set_wind(wind).ok());
    ForceField field;
    field.kind = ForceField::Kind::radial;
    field.center = {0.5 * double(f), 2.0, 0.0};
    field.radius = 6.0;
    field.radial = 15.0;
    ASSERT_TRUE(s.set_force_fields({&field, 1}).ok());
}

TEST_P(StepReplay, FollowsPlanChangesBetweenFrames) {
    std::string no_device;
    auto engine = EngineDevice::create(no_device);
    if (!no_device.empty()) GTEST_SKIP() << no_device;
    ASSERT_TRUE(engine);
    SimulationConfig config;
    config.wind.strength = 6.0;
    config.model.dynamics = GetParam();
    Scene scene = *grid_scene(small_tree(), 6, 5.0, 4);
    scene.lod_budgets = {{3, 1}};
    auto recorded = vulkan::create_simulation(scene, config, engine->context());
    ASSERT_TRUE(recorded.ok()) << recorded.status().message();
    Simulation& sim = *recorded.value();
    std::string skip;
    auto reference = create_simulation_or_skip(scene, config, BackendKind::vulkan, skip);
    ASSERT_TRUE(reference);
    const auto& backend = vulkan_of(sim);
    LodBands bands;
    bands.edges = {100.0};
    bands.fade_steps = 4;
    for (Simulation* s : {&sim, reference.get()}) {
        ASSERT_TRUE(s->reserve_instances(16).ok());
        ASSERT_TRUE(s->set_lod_bands(bands).ok());
    }
    {
        EngineFrames frames(*engine, 3);
        if (HasFailure()) return;
        for (uint32_t f = 0; f < 18; ++f) {
            for (Simulation* s : {&sim, reference.get()}) {
                gust(*s, f);
                if (f == 4) {  // a reset: a one-off pose, the step program stays
                    const uint32_t reset[] = {2};
                    ASSERT_TRUE(s->reset_instances(reset).ok());
                }
                if (f == 6) {  // a tree streams in: a new program
                    const Instance added[] = {{0, {12.0, 0.0, 3.0}, 0.4}};
                    ASSERT_TRUE(s->add_instances(added).ok());
                }
                if (f == 9) {  // switches made at once: a new program
                    const InstanceId ids[] = {InstanceId(0), InstanceId(3)};
                    const uint32_t levels[] = {1, 2};
                    ASSERT_TRUE(s->set_instance_lods(ids, levels).ok());
                }
                if (f == 12) {  // fades that end a few frames later: new programs then
                    const InstanceId ids[] = {InstanceId(1), InstanceId(4)};
                    const uint32_t levels[] = {2, 1};
                    auto requested = s->request_instance_lods(ids, levels);
                    ASSERT_TRUE(requested.ok()) << requested.status().message();
                }
                if (HasFatalFailure()) return;
            }
            const uint64_t secondaries = backend.step_secondaries_recorded();
            const uint64_t replays = backend.step_replays();
            // 1, 2 and 3 steps in turn: the coupled dynamics' load halves and the fades' clock
            // come from the wind table, whatever step count the replayed secondary records.
            const uint32_t steps = 1 + f % 3;
            VkCommandBuffer cmd = frames.begin(f);
            const Status status = vulkan::record_steps(sim, cmd, steps);
            frames.submit(f);
            ASSERT_TRUE(status.ok()) << "frame " << f << ": " << status.message();
            ASSERT_TRUE(reference->step(steps).ok());
            EXPECT_GE(backend.step_replays(), replays + 1) << "frame " << f << " replays its steps";
            if (f == 6 || f == 9)
                EXPECT_GT(backend.step_secondaries_recorded(), secondaries) << "frame " << f << " has a new program";
            if (f == 4 || f == 5)  // a reset's one-off program has a plan of its own
                EXPECT_EQ(backend.step_secondaries_recorded(), secondaries) << "frame " << f << ": live data only";
        }
        frames.wait_all();
    }
    EXPECT_EQ(sim.fading_instance_count(), 0u);
    EXPECT_EQ(*sim.instance_lod(InstanceId(1)), 2u);
    expect_same_outputs(sim, *reference);
    recorded.value().reset();  // before the engine's device
}

INSTANTIATE_TEST_SUITE_P(Dynamics, StepReplay, ::testing::Values(Dynamics::paper, Dynamics::coupled),
                         [](const auto& info) { return info.param == Dynamics::paper ? "paper" : "coupled"; });

// A steady frame loop records the secondaries of its ring's frames once: a per-frame
// re-recording (the cost the replay removes) fails here.
TEST_F(StepReplay, SteadyFramesRecordNoSecondaryAgain) {
    std::string no_device;
    auto engine = EngineDevice::create(no_device);
    if (!no_device.empty()) GTEST_SKIP() << no_device;
    ASSERT_TRUE(engine);
    SimulationConfig config;
    config.wind.strength = 6.0;
    Scene scene = *grid_scene(small_tree(), 4, 5.0, 4);
    vulkan::ExternalContext context = engine->context();
    ASSERT_EQ(context.frames_in_flight, 3u);
    auto recorded = vulkan::create_simulation(scene, config, context);
    ASSERT_TRUE(recorded.ok()) << recorded.status().message();
    Simulation& sim = *recorded.value();
    std::string skip;
    auto reference = create_simulation_or_skip(scene, config, BackendKind::vulkan, skip);
    ASSERT_TRUE(reference);
    const auto& backend = vulkan_of(sim);
    constexpr uint32_t kFrames = 12;
    uint64_t after_first_round = 0;
    {
        EngineFrames frames(*engine, 3);
        if (HasFailure()) return;
        for (uint32_t f = 0; f < kFrames; ++f) {
            for (Simulation* s : {&sim, reference.get()}) gust(*s, f);
            if (HasFatalFailure()) return;
            VkCommandBuffer cmd = frames.begin(f);
            const Status status = vulkan::record_steps(sim, cmd, 2);
            frames.submit(f);
            ASSERT_TRUE(status.ok()) << "frame " << f << ": " << status.message();
            ASSERT_TRUE(reference->step(2).ok());
            if (f == 2) after_first_round = backend.step_secondaries_recorded();
        }
        frames.wait_all();
    }
    EXPECT_EQ(after_first_round, 3u) << "one secondary per frame in flight";
    EXPECT_EQ(backend.step_secondaries_recorded(), after_first_round) << "recorded again in a steady loop";
    EXPECT_EQ(backend.step_replays(), kFrames);
    expect_same_outputs(sim, *reference);
    recorded.value().reset();  // before the engine's device
}

// With the replay off (HMSM_VULKAN_REPLAY_STEPS=0) the steps go into the engine's command buffer
// directly, with the same results.
TEST_F(VulkanTest, RecordedStepsWithoutReplayMatchStep) {
    std::string no_device;
    auto engine = EngineDevice::create(no_device);
    if (!no_device.empty()) GTEST_SKIP() << no_device;
    ASSERT_TRUE(engine);
    detail::vulkan_set_step_replay(false);
    SimulationConfig config;
    config.wind.strength = 6.0;
    Scene scene = *grid_scene(small_tree(), 4, 5.0, 4);
    auto recorded = vulkan::create_simulation(scene, config, engine->context());
    detail::vulkan_set_step_replay(std::nullopt);
    ASSERT_TRUE(recorded.ok()) << recorded.status().message();
    Simulation& sim = *recorded.value();
    std::string skip;
    auto reference = create_simulation_or_skip(scene, config, BackendKind::vulkan, skip);
    ASSERT_TRUE(reference);
    {
        EngineFrames frames(*engine, 3);
        if (HasFailure()) return;
        for (uint32_t f = 0; f < 6; ++f) {
            for (Simulation* s : {&sim, reference.get()}) gust(*s, f);
            if (HasFatalFailure()) return;
            VkCommandBuffer cmd = frames.begin(f);
            const Status status = vulkan::record_steps(sim, cmd, 2);
            frames.submit(f);
            ASSERT_TRUE(status.ok()) << "frame " << f << ": " << status.message();
            ASSERT_TRUE(reference->step(2).ok());
        }
        frames.wait_all();
    }
    EXPECT_EQ(vulkan_of(sim).step_replays(), 0u);
    expect_same_outputs(sim, *reference);
    recorded.value().reset();  // before the engine's device
}

}  // namespace
}  // namespace hmsm::test
