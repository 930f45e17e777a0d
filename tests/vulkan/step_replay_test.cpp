// Recorded steps replayed from secondary command buffers (src/vulkan/step_replay.h): each
// record_steps executes a secondary that holds the step program's commands, recorded again only
// when the program changes. Frames whose live data changes (gusts, a turned wind, a moving force
// field, step counts that shift the load halves of the coupled dynamics) and frames that reset
// a tree (a one-off program) replay the same secondaries; adding a tree, switching levels,
// starting and ending fades record new ones. The
// results must equal the same frames stepped with step(), under synchronization validation.
#include "engine_device.h"
#include "recorded_pair.h"
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

/// The outputs the recorded and the reference simulation must give bit for bit.
constexpr std::initializer_list<Output> kCompared = {Output::node_positions, Output::vertex_positions,
                                                     Output::joint_matrices};

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
    std::string skip;
    RecordedAndReference::Options options;
    options.dynamics = GetParam();
    RecordedAndReference pair = RecordedAndReference::create(options, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(pair.recorded && pair.reference);
    Simulation &sim = *pair.recorded, *reference = pair.reference.get();
    const auto& backend = vulkan_of(sim);
    LodBands bands;
    bands.edges = {100.0};
    bands.fade_steps = 4;
    for (Simulation* s : {&sim, reference}) {
        ASSERT_TRUE(s->reserve_instances(16).ok());
        ASSERT_TRUE(s->set_lod_bands(bands).ok());
    }
    uint64_t secondaries = 0, replays = 0;  // before the frame
    auto change = [&](uint32_t f) {
        for (Simulation* s : {&sim, reference}) {
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
        }
        secondaries = backend.step_secondaries_recorded();
        replays = backend.step_replays();
    };
    // 1, 2 and 3 steps in turn: the coupled dynamics' load halves and the fades' clock come
    // from the wind table, whatever step count the replayed secondary records.
    auto steps = [](uint32_t f) { return 1 + f % 3; };
    auto check = [&](uint32_t f) {
        EXPECT_GE(backend.step_replays(), replays + 1) << "frame " << f << " replays its steps";
        if (f == 6 || f == 9)
            EXPECT_GT(backend.step_secondaries_recorded(), secondaries) << "frame " << f << " has a new program";
        if (f == 4 || f == 5)  // a reset's one-off program has a plan of its own
            EXPECT_EQ(backend.step_secondaries_recorded(), secondaries) << "frame " << f << ": live data only";
    };
    pair.run_frames(18, change, steps, check);
    if (HasFatalFailure()) return;
    EXPECT_EQ(sim.fading_instance_count(), 0u);
    EXPECT_EQ(*sim.instance_lod(InstanceId(1)), 2u);
    pair.expect_same(kCompared);
}

INSTANTIATE_TEST_SUITE_P(Dynamics, StepReplay, ::testing::Values(Dynamics::paper, Dynamics::coupled),
                         [](const auto& info) { return info.param == Dynamics::paper ? "paper" : "coupled"; });

// A steady frame loop records the secondaries of its ring's frames once: a per-frame
// re-recording (the cost the replay removes) fails here.
TEST_F(StepReplay, SteadyFramesRecordNoSecondaryAgain) {
    std::string skip;
    RecordedAndReference::Options options;
    options.trees = 4;
    options.lod_budgets.clear();
    RecordedAndReference pair = RecordedAndReference::create(options, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(pair.recorded && pair.reference);
    ASSERT_EQ(pair.engine->context().frames_in_flight, 3u);
    Simulation &sim = *pair.recorded, *reference = pair.reference.get();
    const auto& backend = vulkan_of(sim);
    constexpr uint32_t kFrames = 12;
    uint64_t after_first_round = 0, copies = 0;
    pair.run_frames(
        kFrames,
        [&](uint32_t f) {
            for (Simulation* s : {&sim, reference}) gust(*s, f);
            copies = backend.engine_copy_commands();
        },
        [](uint32_t) { return 2u; },
        [&](uint32_t f) {
            if (f == 2) after_first_round = backend.step_secondaries_recorded();
            // The gust's wind table (header and step slots) travels in the secondary: past the
            // first frame (its run table) the engine's buffer gets the vkCmdExecuteCommands
            // alone, but in frame 4, whose turned wind rewrites every instance's wind data.
            if (f > 0 && f != 4)
                EXPECT_EQ(backend.engine_copy_commands(), copies) << "copies into the engine's buffer, frame " << f;
        });
    if (HasFatalFailure()) return;
    EXPECT_EQ(after_first_round, 3u) << "one secondary per frame in flight";
    EXPECT_EQ(backend.step_secondaries_recorded(), after_first_round) << "recorded again in a steady loop";
    EXPECT_EQ(backend.step_replays(), kFrames);
    pair.expect_same(kCompared);
}

// The wind header is written only in the frames that change the wind (here 1 and 7); every
// ring slot's copy of the wind table carries it into the frames after, whichever slot wrote it.
TEST_F(StepReplay, WindChangedInOneFrameReachesTheFramesAfterIt) {
    std::string skip;
    RecordedAndReference::Options options;
    options.trees = 3;
    options.lod_budgets.clear();
    RecordedAndReference pair = RecordedAndReference::create(options, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(pair.recorded && pair.reference);
    pair.run_frames(
        11,
        [](Simulation& s, uint32_t f) {
            if (f == 1 || f == 7) gust(s, f);
        },
        2);
    if (HasFatalFailure()) return;
    EXPECT_GE(vulkan_of(*pair.recorded).step_replays(), 11u);
    pair.expect_same(kCompared);
}

// With the replay off (HMSM_VULKAN_REPLAY_STEPS=0) the steps go into the engine's command buffer
// directly, with the same results.
TEST_F(VulkanTest, RecordedStepsWithoutReplayMatchStep) {
    std::string skip;
    RecordedAndReference::Options options;
    options.trees = 4;
    options.lod_budgets.clear();
    options.replay = false;
    RecordedAndReference pair = RecordedAndReference::create(options, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(pair.recorded && pair.reference);
    pair.run_frames(6, gust, 2);
    if (HasFatalFailure()) return;
    EXPECT_EQ(vulkan_of(*pair.recorded).step_replays(), 0u);
    pair.expect_same(kCompared);
}

}  // namespace
}  // namespace hmsm::test
