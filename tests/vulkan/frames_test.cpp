// Frames in flight (hmsm/vulkan.h record_steps, docs/vulkan.md): an engine records the steps
// of each frame into one of three command buffers and submits them without waiting, but for
// the fence of the frame that last used the command buffer; live changes before every frame
// travel through the simulation's ring of frame slots. Synchronization validation (on in
// this suite when the layer is installed) checks the recorded copies and dispatches across the
// overlapping submissions; the results must equal the same frames stepped with step().
#include "engine_device.h"
#include "simulation_access.h"
#include "test_trees.h"
#include "vulkan_test_support.h"

#include "vulkan/frame_ring.h"

#include <hmsm/vulkan.h>


namespace hmsm::test {
namespace {

/// The live changes before frame `f`: a gust every frame, a turn of the wind now and then
/// (which rewrites every instance's wind data), a force field moving every frame, one
/// instance's wind scale, and an instance paused for a few frames.
void change_before_frame(Simulation& s, uint32_t f) {
    Wind wind = s.wind();
    wind.strength = 6.0 + 0.5 * double(f % 5);
    if (f % 4 == 2) wind.direction = {1.0, 0.0, 0.2 * double(f % 3)};
    if (f == 3) wind.profile = WindProfile::turbulent;
    ASSERT_TRUE(s.set_wind(wind).ok());
    ForceField field;
    field.kind = f % 2 ? ForceField::Kind::radial : ForceField::Kind::directional;
    field.center = {0.5 * double(f), 2.0, 0.0};
    field.radius = 6.0;
    field.radial = 15.0;
    field.directional = {0.0, 0.0, 3.0};
    ASSERT_TRUE(s.set_force_fields({&field, 1}).ok());
    ASSERT_TRUE(s.set_instance_wind_scale(f % s.instance_count(), 1.0 + 0.1 * double(f)).ok());
    if (f == 4) ASSERT_TRUE(s.set_instance_active(1, false).ok());
    if (f == 8) ASSERT_TRUE(s.set_instance_active(1, true).ok());
}

/// The first size of the ring's slots: the default, and one so small that the slots grow, also
/// between the writes of one frame.
class FramesInFlight : public VulkanTest, public ::testing::WithParamInterface<uint64_t> {
protected:
    void SetUp() override {
        VulkanTest::SetUp();
        detail::vulkan_set_frame_slot_bytes(GetParam());
    }
    void TearDown() override {
        detail::vulkan_set_frame_slot_bytes(0);
        VulkanTest::TearDown();
    }
};

TEST_P(FramesInFlight, WithLiveChangesMatchStep) {
    std::string no_device;
    auto engine = EngineDevice::create(no_device);
    if (!no_device.empty()) GTEST_SKIP() << no_device;
    ASSERT_TRUE(engine);
    const EngineDevice& device = *engine;
    SimulationConfig config;
    config.wind.strength = 6.0;
    Scene scene = *grid_scene(small_tree(), 5, 5.0, 4);
    vulkan::ExternalContext context = device.context();
    context.frames_in_flight = 4;
    auto recorded = vulkan::create_simulation(scene, config, context);
    ASSERT_TRUE(recorded.ok()) << recorded.status().message();
    Simulation& sim = *recorded.value();
    std::string skip;
    auto reference = create_simulation_or_skip(scene, config, BackendKind::vulkan, skip);
    ASSERT_TRUE(reference);
    const auto& backend = dynamic_cast<const detail::vk::VulkanBackend&>(detail::backend_of(sim));
    EXPECT_EQ(backend.frames_in_flight(), 4u);

    constexpr uint32_t kFrames = 14;
    {
        // Two recordings share frame 1's command buffer, so 3 command buffers hold up to 4
        // recordings; a ring of 4 slots keeps the ring rule.
        EngineFrames frames(device, 3);
        if (HasFailure()) return;
        const uint64_t submissions = backend.submissions();
        for (uint32_t f = 0; f < kFrames; ++f) {
            change_before_frame(sim, f);
            change_before_frame(*reference, f);
            if (HasFatalFailure()) return;
            VkCommandBuffer cmd = frames.begin(f);
            Status status = vulkan::record_steps(sim, cmd, 1 + f % 3);
            ASSERT_TRUE(reference->step(1 + f % 3).ok());
            if (f % 5 == 1 && status.ok()) {
                // A second recording into the same command buffer, after another change: its
                // copies follow the first recording's dispatches.
                change_before_frame(sim, f + 1);
                change_before_frame(*reference, f + 1);
                status = vulkan::record_steps(sim, cmd, 2);
                ASSERT_TRUE(reference->step(2).ok());
            }
            frames.submit(f);
            ASSERT_TRUE(status.ok()) << "frame " << f << ": " << status.message();
        }
        // hmsm neither submitted nor waited: every frame went with the engine's submissions.
        EXPECT_EQ(backend.submissions(), submissions);
        frames.wait_all();
    }
    EXPECT_EQ(sim.steps_done(), reference->steps_done());
    for (Output output : {Output::node_positions, Output::vertex_positions, Output::joint_matrices}) {
        std::vector<float> a, b;
        ASSERT_TRUE(sim.read(output, a).ok());
        ASSERT_TRUE(reference->read(output, b).ok());
        EXPECT_EQ(a, b) << "output " << int(output);
    }
    recorded.value().reset();  // before the engine's device
}

INSTANTIATE_TEST_SUITE_P(SlotBytes, FramesInFlight, ::testing::Values(uint64_t(0), uint64_t(256)),
                         [](const auto& info) { return info.param ? "slots_of_" + std::to_string(info.param) + "_bytes" : std::string("default_slots"); });

TEST_F(VulkanTest, FramesInFlightOutsideItsRangeIsRefused) {
    std::string no_device;
    auto engine = EngineDevice::create(no_device);
    if (!no_device.empty()) GTEST_SKIP() << no_device;
    ASSERT_TRUE(engine);
    vulkan::ExternalContext context = engine->context();
    for (uint32_t frames : {0u, 17u}) {
        context.frames_in_flight = frames;
        auto sim = vulkan::create_simulation(single_tree_scene(small_tree()), {}, context);
        ASSERT_FALSE(sim.ok());
        EXPECT_EQ(sim.status().code(), ErrorCode::invalid_argument);
        EXPECT_NE(sim.status().message().find("frames_in_flight must be 1 to 16 (got " + std::to_string(frames)),
                  std::string::npos)
            << sim.status().message();
    }
}

}  // namespace
}  // namespace hmsm::test
