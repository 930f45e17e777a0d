#include "vulkan_test_support.h"

#include <hmsm/vulkan.h>

#include "vulkan/validation.h"

#include <cmath>
#include <limits>
#include <mutex>

namespace hmsm::test {
namespace {

struct Messages {
    std::mutex mutex;
    std::vector<std::string> list;
    bool enabled = false;
};
Messages& messages() {
    static Messages m;
    return m;
}

}  // namespace

bool install_vulkan_validation() {
    if (!detail::vulkan_validation_layer_available()) return false;
    detail::vulkan_set_validation(true, [](const std::string& message) {
        std::lock_guard lock(messages().mutex);
        messages().list.push_back(message);
    });
    messages().enabled = true;
    return true;
}

bool vulkan_validation_enabled() { return messages().enabled; }

std::vector<std::string> take_validation_messages() {
    std::lock_guard lock(messages().mutex);
    return std::exchange(messages().list, {});
}

std::unique_ptr<detail::Backend> create_vulkan_or_skip(std::string& skip) {
    auto backend = detail::create_vulkan_backend();
    if (!backend.ok()) {
        if (backend.status().code() == ErrorCode::no_device) skip = backend.status().message();
        else ADD_FAILURE() << backend.status().message();
        return nullptr;
    }
    return std::move(backend).value();
}

std::vector<double> read_buffer(const detail::Backend& backend, detail::BufferId id, uint64_t count) {
    std::vector<double> values(count * detail::shape_scalars(detail::buffer_info(id).shape));
    Status s = backend.read(id, 0, count, values.data(), detail::Scalar::f64);
    EXPECT_TRUE(s.ok()) << s.message();
    return values;
}

double relative_difference(const std::vector<double>& a, const std::vector<double>& b) {
    if (a.size() != b.size()) return std::numeric_limits<double>::infinity();
    double scale = 1.0, diff = 0.0;
    for (size_t i = 0; i < a.size(); ++i) {
        if (!std::isfinite(a[i]) || !std::isfinite(b[i])) return std::numeric_limits<double>::infinity();
        scale = std::max(scale, std::abs(b[i]));
        diff = std::max(diff, std::abs(a[i] - b[i]));
    }
    return diff / scale;
}

vulkan::ExternalContext engine_context(const detail::vk::Device& device) {
    vulkan::ExternalContext context;
    context.instance = device.instance();
    context.physical_device = device.physical_device();
    context.device = device.handle();
    context.queue = device.queue();
    context.queue_family_index = device.queue_family();
    return context;
}

void record_steps_on_engine_queue(const detail::vk::Device& device, Simulation& simulation, uint32_t steps) {
    const VolkDeviceTable& vk = device.vk();
    VkCommandPoolCreateInfo pool_info{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pool_info.queueFamilyIndex = device.queue_family();
    VkCommandPool pool;
    ASSERT_EQ(vk.vkCreateCommandPool(device.handle(), &pool_info, nullptr, &pool), VK_SUCCESS);
    VkCommandBufferAllocateInfo allocate{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    allocate.commandPool = pool;
    allocate.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    allocate.commandBufferCount = 1;
    VkCommandBuffer cmd;
    ASSERT_EQ(vk.vkAllocateCommandBuffers(device.handle(), &allocate, &cmd), VK_SUCCESS);
    VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    ASSERT_EQ(vk.vkBeginCommandBuffer(cmd, &begin), VK_SUCCESS);
    const Status recorded = vulkan::record_steps(simulation, cmd, steps);
    EXPECT_TRUE(recorded.ok()) << recorded.message();
    ASSERT_EQ(vk.vkEndCommandBuffer(cmd), VK_SUCCESS);
    VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    submit.commandBufferCount = 1;
    submit.pCommandBuffers = &cmd;
    EXPECT_EQ(vk.vkQueueSubmit(device.queue(), 1, &submit, VK_NULL_HANDLE), VK_SUCCESS);
    EXPECT_EQ(vk.vkQueueWaitIdle(device.queue()), VK_SUCCESS);
    vk.vkDestroyCommandPool(device.handle(), pool, nullptr);
}

}  // namespace hmsm::test
