// A Vulkan device for the backend: either created by hmsm (its own instance, a physical device
// chosen by type or by HMSM_VULKAN_DEVICE, one compute queue) or adopted from an engine
// (hmsm::vulkan::ExternalContext, never destroyed by hmsm). Device-level entry points come from
// a per-device volk table, so several devices (hmsm's and an engine's) can coexist.
#pragma once

#include <hmsm/status.h>
#include <hmsm/vulkan.h>

#include "volk_private.h"

#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace hmsm::detail::vk {

/// The limits the backend must respect; queried, never assumed.
struct DeviceLimits {
    VkDeviceSize max_storage_buffer_range = 0;
    VkDeviceSize max_memory_allocation_size = 0;
    VkDeviceSize min_storage_buffer_offset_alignment = 1;
    uint32_t max_workgroup_count[3] = {};
    uint32_t max_workgroup_size_x = 0;
    uint32_t max_workgroup_invocations = 0;
    uint32_t max_shared_memory_bytes = 0;  ///< maxComputeSharedMemorySize
    uint32_t max_push_constants_size = 0;
    uint32_t max_storage_buffers_per_stage = 0;
    uint32_t max_storage_buffers_per_set = 0;
    /// Nanoseconds per timestamp tick; 0 when the queue has no timestamps.
    double timestamp_period_ns = 0.0;
    uint32_t timestamp_valid_bits = 0;
};

class Device {
public:
    /// hmsm's own instance and device. HMSM_VULKAN_DEVICE (an index into the enumeration or a
    /// case-insensitive substring of the device name) overrides the choice of discrete GPU,
    /// then integrated GPU, then anything else (a CPU driver such as lavapipe last).
    static Result<std::shared_ptr<Device>> create();
    /// Wraps an engine's device; checks that it can run hmsm (Vulkan 1.1, a compute queue).
    static Result<std::shared_ptr<Device>> adopt(const hmsm::vulkan::ExternalContext& context);
    ~Device();
    Device(const Device&) = delete;
    Device& operator=(const Device&) = delete;

    const VolkDeviceTable& vk() const { return table_; }
    VkInstance instance() const { return instance_; }
    VkDevice handle() const { return device_; }
    VkPhysicalDevice physical_device() const { return physical_; }
    VkQueue queue() const { return queue_; }
    uint32_t queue_family() const { return queue_family_; }
    const DeviceLimits& limits() const { return limits_; }
    const VkPhysicalDeviceMemoryProperties& memory_properties() const { return memory_; }
    std::string name() const { return properties_.deviceName; }
    bool is_cpu() const { return properties_.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU; }
    bool is_external() const { return !owned_; }
    /// After the device stopped making progress (a wait timed out): the destructor neither
    /// waits for it nor destroys it, so the process can still report the error and exit.
    void abandon() { abandoned_ = true; }

    /// vkQueueSubmit of one submission, serialized with every other submission hmsm makes to
    /// this device's queue (simulations sharing an hmsm::vulkan::Context may step on several
    /// threads).
    VkResult submit(const VkSubmitInfo& info, VkFence fence) const {
        std::lock_guard lock(queue_mutex_);
        return table_.vkQueueSubmit(queue_, 1, &info, fence);
    }

    /// Ok, or an internal error carrying the first validation message reported since the last
    /// call (always ok when validation is off). Clears the messages.
    Status take_validation_messages();

private:
    Device() = default;
    Status create_instance();
    Status choose_physical_device();
    Status create_device();
    Status load_device_info();
    static VkBool32 VKAPI_PTR on_message(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                         VkDebugUtilsMessageTypeFlagsEXT types,
                                         const VkDebugUtilsMessengerCallbackDataEXT* data,
                                         void* user);

    bool owned_ = true;
    bool abandoned_ = false;
    VkInstance instance_ = VK_NULL_HANDLE;
    VkDebugUtilsMessengerEXT messenger_ = VK_NULL_HANDLE;
    PFN_vkDestroyDebugUtilsMessengerEXT destroy_messenger_ = nullptr;
    VkPhysicalDevice physical_ = VK_NULL_HANDLE;
    VkDevice device_ = VK_NULL_HANDLE;
    VkQueue queue_ = VK_NULL_HANDLE;
    uint32_t queue_family_ = 0;
    VolkDeviceTable table_{};
    VkPhysicalDeviceProperties properties_{};
    VkPhysicalDeviceMemoryProperties memory_{};
    DeviceLimits limits_;

    mutable std::mutex queue_mutex_;
    std::mutex messages_mutex_;
    std::vector<std::string> messages_;
};

}  // namespace hmsm::detail::vk
