// hmsm::vulkan::Context: several simulations on one device hmsm created, stepping on two
// threads at once, with the results of simulations on devices of their own.
#include "test_trees.h"
#include "vulkan_test_support.h"

#include <hmsm/vulkan.h>

#include <thread>

namespace hmsm::test {
namespace {

TEST_F(VulkanTest, SimulationsOnOneContextShareItsDeviceAndStepOnSeveralThreads) {
    auto context = vulkan::create_context();
    if (!context.ok() && context.status().code() == ErrorCode::no_device) GTEST_SKIP() << context.status().message();
    ASSERT_TRUE(context.ok()) << context.status().message();
    SimulationConfig config;
    config.wind.strength = 6.0;
    const Scene scenes[2] = {*grid_scene(small_tree(), 3, 5.0, 4), *grid_scene(deep_tree(5), 5, 4.0, 7)};
    std::unique_ptr<Simulation> shared[2];
    for (int k = 0; k < 2; ++k) {
        auto sim = vulkan::create_simulation(scenes[k], config, *context);
        ASSERT_TRUE(sim.ok()) << sim.status().message();
        shared[k] = std::move(sim).value();
    }
    auto first = vulkan::device_handles(*shared[0]), second = vulkan::device_handles(*shared[1]);
    ASSERT_TRUE(first.ok() && second.ok());
    EXPECT_EQ(first->device, second->device);
    EXPECT_EQ(first->queue, second->queue);
    context->reset();  // the simulations keep the device

    // Both step at once; hmsm serializes their submissions to the one queue.
    Status other;
    std::thread thread([&] {
        for (int i = 0; i < 8 && other.ok(); ++i) other = shared[1]->step(3);
    });
    Status mine;
    for (int i = 0; i < 8 && mine.ok(); ++i) mine = shared[0]->step(3);
    thread.join();
    ASSERT_TRUE(mine.ok()) << mine.message();
    ASSERT_TRUE(other.ok()) << other.message();

    for (int k = 0; k < 2; ++k) {
        std::string skip;
        auto own = create_simulation_or_skip(scenes[k], config, BackendKind::vulkan, skip);
        ASSERT_TRUE(own);
        ASSERT_TRUE(own->step(24).ok());
        std::vector<float> a, b;
        ASSERT_TRUE(shared[k]->read(Output::vertex_positions, a).ok());
        ASSERT_TRUE(own->read(Output::vertex_positions, b).ok());
        EXPECT_EQ(a, b) << "simulation " << k;
    }
    EXPECT_EQ(vulkan::create_simulation(scenes[0], config, std::shared_ptr<vulkan::Context>()).status().code(),
              ErrorCode::invalid_argument);
}

}  // namespace
}  // namespace hmsm::test
