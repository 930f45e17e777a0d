// Growth past the capacity on Vulkan (src/vulkan/growth.cpp): a failed allocation leaves the
// simulation as it was, and a scene that the growth would cut into windows falls back to
// uploading the scene anew, with the results of a growth on the device.
#include "simulation_access.h"
#include "test_trees.h"
#include "vulkan_test_support.h"

#include "capacity_growth.h"
#include "device_words.h"
#include "vulkan/fault_injection.h"
#include "vulkan/windows.h"

namespace hmsm::test {
namespace {

using detail::device_growths_of;
using detail::full_uploads_of;

const detail::vk::VulkanBackend& vulkan_of(const Simulation& sim) {
    return dynamic_cast<const detail::vk::VulkanBackend&>(hmsm::detail::backend_of(sim));
}

/// Every output, as float.
std::vector<std::vector<float>> outputs_of(const Simulation& sim) { return every_output(sim); }

TEST_F(VulkanTest, FailedGrowthLeavesTheSimulationAsItWas) {
    std::string skip;
    const Scene scene = *grid_scene(small_tree(), 3, 5.0, 2);
    auto plain = create_simulation_or_skip(scene, windy_config(), BackendKind::vulkan, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    std::unique_ptr<Simulation> failing;
    {
        struct Fault {
            Fault() { detail::vulkan_inject_fault(detail::VulkanFault::out_of_device_memory_at_growth); }
            ~Fault() { detail::vulkan_inject_fault(detail::VulkanFault::none); }
        } fault;
        failing = create_simulation_or_skip(scene, windy_config(), BackendKind::vulkan, skip);
    }
    ASSERT_TRUE(plain && failing);
    ASSERT_TRUE(plain->step(10).ok());
    ASSERT_TRUE(failing->step(10).ok());
    const detail::SceneData before = detail::scene_data_of(*failing);
    const Instance added[] = {{0, {20, 0, 0}, 0.4}};
    const Status refused = failing->add_instances(added);
    EXPECT_EQ(refused.code(), ErrorCode::out_of_memory) << refused.message();
    EXPECT_NE(refused.message().find("VK_ERROR_OUT_OF_DEVICE_MEMORY"), std::string::npos) << refused.message();
    const detail::SceneData& after = detail::scene_data_of(*failing);
    EXPECT_EQ(after.chain_capacity, before.chain_capacity);
    EXPECT_EQ(after.instance_capacity, before.instance_capacity);
    EXPECT_EQ(failing->instance_count(), plain->instance_count());
    EXPECT_EQ(device_growths_of(*failing), 0u);
    EXPECT_EQ(full_uploads_of(*failing), 0u);
    ASSERT_TRUE(plain->step(10).ok());
    ASSERT_TRUE(failing->step(10).ok());
    EXPECT_TRUE(same_bits(outputs_of(*failing), outputs_of(*plain))) << "the failed add changed nothing";
}

TEST_F(VulkanTest, GrowthThatWouldNeedWindowsUploadsAnew) {
    std::string skip;
    const Scene scene = *grid_scene(small_tree(), 4, 5.0, 5);
    auto grown = create_simulation_or_skip(scene, windy_config(), BackendKind::vulkan, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(grown);
    // A window as large as the largest state buffer now: the scene fits it, the grown one not.
    const detail::SceneData& data = detail::scene_data_of(*grown);
    uint64_t largest = 0;
    for (const detail::BufferInfo& info : detail::kBufferTable)
        if (detail::sized_by_capacity(info.id))
            largest = std::max(largest, data.element_count(info.id) * detail::device_element_bytes(info.id));
    std::unique_ptr<Simulation> windowed;
    {
        const struct Window {
            explicit Window(uint64_t bytes) { detail::vulkan_set_window_bytes(bytes); }
            ~Window() { detail::vulkan_set_window_bytes(0); }
        } window(largest + 256);
        windowed = create_simulation_or_skip(scene, windy_config(), BackendKind::vulkan, skip);
    }
    ASSERT_TRUE(windowed);
    ASSERT_FALSE(vulkan_of(*windowed).window_plan().split()) << "the scene starts in one window";
    for (Simulation* sim : {grown.get(), windowed.get()}) {
        ASSERT_TRUE(sim->step(12).ok());
        const Instance added[] = {{0, {30, 0, 0}, 0.2}, {0, {-30, 0, 4}, 1.2, 0.7, 0.4}};
        ASSERT_TRUE(sim->add_instances(added).ok());
        ASSERT_TRUE(sim->step(12).ok());
    }
    EXPECT_TRUE(vulkan_of(*windowed).window_plan().split()) << "the grown scene needs windows";
    EXPECT_EQ(full_uploads_of(*windowed), 1u);
    EXPECT_EQ(device_growths_of(*windowed), 0u);
    EXPECT_EQ(full_uploads_of(*grown), 0u);
    EXPECT_EQ(device_growths_of(*grown), 1u);
    EXPECT_TRUE(same_bits(outputs_of(*windowed), outputs_of(*grown)));
}

}  // namespace
}  // namespace hmsm::test
