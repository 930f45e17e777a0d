// hmsm/vulkan.h: a simulation on an engine's device, steps recorded into the engine's command
// buffer, and the shared output buffers.
#include "engine_device.h"
#include "simulation_access.h"
#include "test_trees.h"
#include "vulkan_test_support.h"

#include "common/octahedral.h"

#include <hmsm/vulkan.h>

namespace hmsm::test {
namespace {

TEST_F(VulkanTest, RecordedStepsApplyLiveChanges) {
    // Live changes made before record_steps take effect in the recorded steps, as in step().
    std::string no_device;
    auto engine = EngineDevice::create(no_device);
    if (!no_device.empty()) GTEST_SKIP() << no_device;
    ASSERT_TRUE(engine);
    const EngineDevice& device = *engine;
    SimulationConfig config;
    config.wind.strength = 6.0;
    Scene scene = *grid_scene(small_tree(), 4, 5.0, 4);
    auto shared = vulkan::create_simulation(scene, config, device.context());
    ASSERT_TRUE(shared.ok()) << shared.status().message();
    Simulation& sim = *shared.value();
    std::string skip;
    auto reference = create_simulation_or_skip(scene, config, BackendKind::vulkan, skip);
    ASSERT_TRUE(reference);
    auto change = [](Simulation& s) {
        Wind wind = s.wind();
        wind.profile = WindProfile::turbulent;
        wind.frequency = 0.5;
        ASSERT_TRUE(s.set_wind(wind).ok());
        ForceField field;
        field.kind = ForceField::Kind::radial;
        field.center = {0, 2, 0};
        field.radius = 8.0;
        field.radial = 20.0;
        ASSERT_TRUE(s.set_force_fields({&field, 1}).ok());
        ASSERT_TRUE(s.set_instance_wind_scale(1, 2.0).ok());
        ASSERT_TRUE(s.set_instance_active(2, false).ok());
        const uint64_t gone[] = {3};
        ASSERT_TRUE(s.remove_instances(gone).ok());
    };
    ASSERT_TRUE(sim.step(10).ok());
    ASSERT_TRUE(reference->step(10).ok());
    change(sim);
    change(*reference);
    record_steps_on_engine_queue(device, sim, 25);
    if (HasFatalFailure()) return;
    ASSERT_TRUE(reference->step(25).ok());
    std::vector<float> a, b;
    ASSERT_TRUE(sim.read(Output::node_positions, a).ok());
    ASSERT_TRUE(reference->read(Output::node_positions, b).ok());
    EXPECT_EQ(a, b);
    EXPECT_NE(vulkan::record_steps(sim, VkCommandBuffer(VK_NULL_HANDLE), 257).message().find("at most 256"), std::string::npos);
    shared.value().reset();
}

TEST_F(VulkanTest, EngineDeviceWithRecordedStepsMatchesOwnDevice) {
    // The "engine": a device hmsm did not create for this simulation.
    std::string no_device;
    auto engine = EngineDevice::create(no_device);
    if (!no_device.empty()) GTEST_SKIP() << no_device;
    ASSERT_TRUE(engine);
    const EngineDevice& device = *engine;
    const vulkan::ExternalContext context = device.context();

    SimulationConfig config;
    config.wind.strength = 6.0;
    Scene scene = *grid_scene(small_tree(), 3, 5.0, 4);
    auto shared = vulkan::create_simulation(scene, config, context);
    ASSERT_TRUE(shared.ok()) << shared.status().message();
    Simulation& sim = *shared.value();
    auto handles = vulkan::device_handles(sim);
    ASSERT_TRUE(handles.ok());
    EXPECT_EQ(handles->device, context.device);

    std::string skip;
    auto reference = create_simulation_or_skip(scene, config, BackendKind::vulkan, skip);
    ASSERT_TRUE(reference);

    // 10 steps submitted by hmsm, then 20 recorded into the engine's command buffer.
    ASSERT_TRUE(sim.step(10).ok());
    record_steps_on_engine_queue(device, sim, 20);
    if (HasFatalFailure()) return;
    EXPECT_EQ(sim.steps_done(), 30u);

    ASSERT_TRUE(reference->step(30).ok());
    for (Output output : {Output::node_positions, Output::vertex_positions, Output::vertex_normals}) {
        std::vector<float> a, b;
        ASSERT_TRUE(sim.read(output, a).ok());
        ASSERT_TRUE(reference->read(output, b).ok());
        EXPECT_EQ(a, b) << "output " << int(output);
    }

    auto buffers = vulkan::shared_buffers(sim);
    ASSERT_TRUE(buffers.ok());
    EXPECT_NE(buffers->vertex_positions.buffer, VK_NULL_HANDLE);
    EXPECT_EQ(buffers->vertex_positions.count, sim.vertex_count());
    EXPECT_EQ(buffers->vertex_normals.count, sim.vertex_count());
    EXPECT_EQ(buffers->node_positions.count, sim.node_count());
    EXPECT_EQ(buffers->vertex_positions.stride, 16u);
    EXPECT_EQ(buffers->node_positions.size, sim.node_count() * 16);
    shared.value().reset();  // before the engine's device goes away
}

TEST_F(VulkanTest, PackedLayoutSharesPositionsWithNormalWordsAndNoNormalBuffer) {
    SimulationConfig config;
    config.wind.strength = 6.0;
    config.vertex_layout = VertexLayout::packed;
    Scene scene = *grid_scene(small_tree(), 3, 5.0, 4);
    std::string skip;
    auto sim = create_simulation_or_skip(scene, config, BackendKind::vulkan, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(sim);
    ASSERT_TRUE(sim->step(12).ok());
    auto buffers = vulkan::shared_buffers(*sim);
    ASSERT_TRUE(buffers.ok()) << buffers.status().message();
    EXPECT_EQ(buffers->vertex_layout, VertexLayout::packed);
    EXPECT_EQ(buffers->vertex_positions.count, sim->vertex_count());
    EXPECT_EQ(buffers->vertex_positions.stride, 16u);
    EXPECT_EQ(buffers->vertex_normals.buffer, VK_NULL_HANDLE);
    EXPECT_EQ(buffers->vertex_normals.count, 0u);
    EXPECT_EQ(buffers->vertex_normals.size, 0u);

    // What the shared buffer holds: xyz as read() returns them, w the word read() decodes.
    std::vector<float> raw(4 * sim->vertex_count()), positions, normals;
    ASSERT_TRUE(hmsm::detail::backend_of(*sim).read(detail::BufferId::vertex_position, 0, sim->vertex_count(), raw.data(),
                                    detail::Scalar::f32).ok());
    ASSERT_TRUE(sim->read(Output::vertex_positions, positions).ok());
    ASSERT_TRUE(sim->read(Output::vertex_normals, normals).ok());
    for (uint64_t v = 0; v < sim->vertex_count(); ++v) {
        for (int k = 0; k < 3; ++k) ASSERT_EQ(raw[4 * v + k], positions[3 * v + k]) << "vertex " << v;
        const auto n = detail::decode_normal_word<float>(detail::bits_from_float(raw[4 * v + 3]));
        ASSERT_EQ(n.x, normals[3 * v]) << "vertex " << v;
        ASSERT_EQ(n.y, normals[3 * v + 1]) << "vertex " << v;
        ASSERT_EQ(n.z, normals[3 * v + 2]) << "vertex " << v;
    }

    config.vertex_layout = VertexLayout::separate;
    auto separate = create_simulation_or_skip(scene, config, BackendKind::vulkan, skip);
    ASSERT_TRUE(separate);
    auto separate_buffers = vulkan::shared_buffers(*separate);
    ASSERT_TRUE(separate_buffers.ok());
    EXPECT_EQ(separate_buffers->vertex_layout, VertexLayout::separate);
    EXPECT_EQ(separate_buffers->vertex_normals.count, separate->vertex_count());
}

TEST_F(VulkanTest, InteropRefusesOtherBackends) {
    SimulationConfig config;
    config.backend = BackendKind::cpu64;
    auto sim = Simulation::create(single_tree_scene(small_tree()), config);
    ASSERT_TRUE(sim.ok());
    auto buffers = vulkan::shared_buffers(*sim.value());
    EXPECT_EQ(buffers.status().code(), ErrorCode::invalid_argument);
    EXPECT_EQ(vulkan::record_steps(*sim.value(), VkCommandBuffer(VK_NULL_HANDLE)).code(),
              ErrorCode::invalid_argument);
    vulkan::ExternalContext empty;
    EXPECT_EQ(vulkan::create_simulation(single_tree_scene(small_tree()), {}, empty).status().code(),
              ErrorCode::invalid_argument);
}

}  // namespace
}  // namespace hmsm::test
