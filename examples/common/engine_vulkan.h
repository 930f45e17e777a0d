// An engine's own Vulkan setup, as the examples use it: the engine (not hmsm) creates the
// instance (with VK_LAYER_KHRONOS_validation and synchronization validation when the layer is
// installed), picks a device with one graphics + compute queue family, and runs F frames in
// flight, each with a command buffer and a fence. It calls the system Vulkan loader directly;
// hmsm keeps its own entry points private, so both live in one process.
#pragma once

#include <vulkan/vulkan.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace engine {

/// A failed Vulkan call or a missing capability, with what was being done.
struct VulkanError : std::runtime_error {
    using std::runtime_error::runtime_error;
};
/// No Vulkan device can run the example (a reason to skip, not a failure).
struct NoDevice : std::runtime_error {
    using std::runtime_error::runtime_error;
};

inline void check(VkResult result, const char* what) {
    if (result != VK_SUCCESS) throw VulkanError(std::string(what) + " failed (VkResult " + std::to_string(int(result)) + ")");
}

/// What the engine asks of its device.
struct DeviceOptions {
    /// A missing validation layer is an error instead of a note.
    bool require_validation = false;
    /// A graphics queue (with compute) and stores from vertex shaders; otherwise compute only.
    bool graphics = true;
    /// Receives every validation message; unset, they are printed to stderr. Either way they
    /// are counted: an engine loop that ends with any of them has failed.
    std::function<void(const char*)> on_validation_message;
};

/// The engine's instance, device and queue.
class Device {
public:
    explicit Device(DeviceOptions options) : options_(std::move(options)) {
        create_instance();
        choose_device();
        create_device();
    }
    ~Device() {
        if (device_) vkDestroyDevice(device_, nullptr);
        if (messenger_) {
            auto destroy = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
                vkGetInstanceProcAddr(instance_, "vkDestroyDebugUtilsMessengerEXT"));
            if (destroy) destroy(instance_, messenger_, nullptr);
        }
        if (instance_) vkDestroyInstance(instance_, nullptr);
    }
    Device(const Device&) = delete;
    Device& operator=(const Device&) = delete;

    VkInstance instance() const { return instance_; }
    VkPhysicalDevice physical_device() const { return physical_; }
    VkDevice handle() const { return device_; }
    VkQueue queue() const { return queue_; }
    uint32_t queue_family() const { return family_; }
    bool validating() const { return messenger_ != VK_NULL_HANDLE; }
    uint64_t validation_messages() const { return messages_; }

    /// A memory type with `required` properties among `type_bits`.
    uint32_t memory_type(uint32_t type_bits, VkMemoryPropertyFlags required) const {
        VkPhysicalDeviceMemoryProperties memory;
        vkGetPhysicalDeviceMemoryProperties(physical_, &memory);
        for (uint32_t i = 0; i < memory.memoryTypeCount; ++i)
            if ((type_bits & (1u << i)) && (memory.memoryTypes[i].propertyFlags & required) == required) return i;
        throw VulkanError("no memory type with properties " + std::to_string(required));
    }

private:
    static VKAPI_ATTR VkBool32 VKAPI_CALL on_message(VkDebugUtilsMessageSeverityFlagBitsEXT,
                                                      VkDebugUtilsMessageTypeFlagsEXT,
                                                      const VkDebugUtilsMessengerCallbackDataEXT* data, void* user) {
        Device& device = *static_cast<Device*>(user);
        ++device.messages_;
        if (device.options_.on_validation_message) device.options_.on_validation_message(data->pMessage);
        else std::fprintf(stderr, "validation: %s\n", data->pMessage);
        return VK_FALSE;
    }

    static bool layer_present(const char* name) {
        uint32_t count = 0;
        vkEnumerateInstanceLayerProperties(&count, nullptr);
        std::vector<VkLayerProperties> layers(count);
        vkEnumerateInstanceLayerProperties(&count, layers.data());
        for (const auto& layer : layers)
            if (std::strcmp(layer.layerName, name) == 0) return true;
        return false;
    }

    void create_instance() {
        VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
        app.pApplicationName = "hmsm engine loop";
        app.apiVersion = VK_API_VERSION_1_1;
        VkInstanceCreateInfo info{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
        info.pApplicationInfo = &app;
        const char* layers[] = {"VK_LAYER_KHRONOS_validation"};
        const char* extensions[] = {VK_EXT_DEBUG_UTILS_EXTENSION_NAME, VK_EXT_VALIDATION_FEATURES_EXTENSION_NAME};
        VkValidationFeatureEnableEXT enables[] = {VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT};
        VkValidationFeaturesEXT features{VK_STRUCTURE_TYPE_VALIDATION_FEATURES_EXT};
        features.enabledValidationFeatureCount = 1;
        features.pEnabledValidationFeatures = enables;
        VkDebugUtilsMessengerCreateInfoEXT messenger{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
        messenger.pNext = &features;
        messenger.messageSeverity =
            VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
        messenger.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT |
                                VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                                VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
        messenger.pfnUserCallback = &Device::on_message;
        messenger.pUserData = this;
        const bool validate = layer_present(layers[0]);
        if (!validate && options_.require_validation) throw VulkanError("VK_LAYER_KHRONOS_validation is not installed");
        if (!validate) std::fprintf(stderr, "note: VK_LAYER_KHRONOS_validation is not installed; running without it\n");
        if (validate) {
            info.enabledLayerCount = 1;
            info.ppEnabledLayerNames = layers;
            info.enabledExtensionCount = 2;
            info.ppEnabledExtensionNames = extensions;
            info.pNext = &messenger;
        }
        const VkResult created = vkCreateInstance(&info, nullptr, &instance_);
        if (created == VK_ERROR_INCOMPATIBLE_DRIVER) throw NoDevice("no Vulkan driver");
        check(created, "vkCreateInstance");
        if (validate) {
            auto create = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
                vkGetInstanceProcAddr(instance_, "vkCreateDebugUtilsMessengerEXT"));
            if (!create) throw VulkanError("VK_EXT_debug_utils entry points missing");
            messenger.pNext = nullptr;
            check(create(instance_, &messenger, nullptr, &messenger_), "vkCreateDebugUtilsMessengerEXT");
        }
    }

    /// The first device with Vulkan 1.1 and a compute queue family; with `graphics`, a
    /// graphics + compute family and stores from vertex shaders (the engine loop writes its
    /// skinned vertices out for checking).
    void choose_device() {
        uint32_t count = 0;
        check(vkEnumeratePhysicalDevices(instance_, &count, nullptr), "vkEnumeratePhysicalDevices");
        std::vector<VkPhysicalDevice> devices(count);
        check(vkEnumeratePhysicalDevices(instance_, &count, devices.data()), "vkEnumeratePhysicalDevices");
        for (VkPhysicalDevice candidate : devices) {
            VkPhysicalDeviceProperties properties;
            vkGetPhysicalDeviceProperties(candidate, &properties);
            VkPhysicalDeviceFeatures features;
            vkGetPhysicalDeviceFeatures(candidate, &features);
            if (properties.apiVersion < VK_API_VERSION_1_1) continue;
            if (options_.graphics && !features.vertexPipelineStoresAndAtomics) continue;
            uint32_t families = 0;
            vkGetPhysicalDeviceQueueFamilyProperties(candidate, &families, nullptr);
            std::vector<VkQueueFamilyProperties> list(families);
            vkGetPhysicalDeviceQueueFamilyProperties(candidate, &families, list.data());
            for (uint32_t f = 0; f < families; ++f) {
                const VkQueueFlags wanted = options_.graphics ? VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT
                                                              : VK_QUEUE_COMPUTE_BIT;
                if ((list[f].queueFlags & wanted) != wanted) continue;
                physical_ = candidate;
                family_ = f;
                return;
            }
        }
        throw NoDevice(options_.graphics ? "no Vulkan 1.1 device with a graphics + compute queue and vertex-shader stores"
                                         : "no Vulkan 1.1 device with a compute queue");
    }

    void create_device() {
        const float priority = 1.0f;
        VkDeviceQueueCreateInfo queue{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
        queue.queueFamilyIndex = family_;
        queue.queueCount = 1;
        queue.pQueuePriorities = &priority;
        VkPhysicalDeviceFeatures features{};
        features.vertexPipelineStoresAndAtomics = options_.graphics ? VK_TRUE : VK_FALSE;
        VkDeviceCreateInfo info{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
        info.queueCreateInfoCount = 1;
        info.pQueueCreateInfos = &queue;
        info.pEnabledFeatures = &features;
        check(vkCreateDevice(physical_, &info, nullptr, &device_), "vkCreateDevice");
        vkGetDeviceQueue(device_, family_, 0, &queue_);
    }

    DeviceOptions options_;
    VkInstance instance_ = VK_NULL_HANDLE;
    VkDebugUtilsMessengerEXT messenger_ = VK_NULL_HANDLE;
    VkPhysicalDevice physical_ = VK_NULL_HANDLE;
    uint32_t family_ = 0;
    VkDevice device_ = VK_NULL_HANDLE;
    VkQueue queue_ = VK_NULL_HANDLE;
    uint64_t messages_ = 0;
};

/// F frames in flight: frame n records into command buffer n % F after waiting for the fence
/// of frame n - F, and is submitted with its fence without waiting.
class Frames {
public:
    Frames(const Device& device, uint32_t frames) : Frames(device.handle(), device.queue(), device.queue_family(), frames) {}
    /// On a device and queue the engine has from elsewhere (e.g. hmsm::vulkan::device_handles).
    Frames(VkDevice device, VkQueue queue, uint32_t queue_family, uint32_t frames)
        : device_(device), queue_(queue), commands_(frames), fences_(frames) {
        VkCommandPoolCreateInfo pool{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
        pool.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
        pool.queueFamilyIndex = queue_family;
        check(vkCreateCommandPool(device_, &pool, nullptr, &pool_), "vkCreateCommandPool");
        VkCommandBufferAllocateInfo allocate{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
        allocate.commandPool = pool_;
        allocate.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
        allocate.commandBufferCount = frames;
        check(vkAllocateCommandBuffers(device_, &allocate, commands_.data()), "vkAllocateCommandBuffers");
        VkFenceCreateInfo fence{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
        fence.flags = VK_FENCE_CREATE_SIGNALED_BIT;
        for (VkFence& f : fences_) check(vkCreateFence(device_, &fence, nullptr, &f), "vkCreateFence");
    }
    ~Frames() {
        vkQueueWaitIdle(queue_);
        for (VkFence f : fences_) vkDestroyFence(device_, f, nullptr);
        vkDestroyCommandPool(device_, pool_, nullptr);
    }
    Frames(const Frames&) = delete;
    Frames& operator=(const Frames&) = delete;

    uint32_t count() const { return uint32_t(commands_.size()); }
    /// Waits for the frame that last used slot `frame % F`, then begins its command buffer.
    VkCommandBuffer begin(uint64_t frame) {
        const size_t k = frame % commands_.size();
        check(vkWaitForFences(device_, 1, &fences_[k], VK_TRUE, UINT64_MAX), "vkWaitForFences");
        check(vkResetFences(device_, 1, &fences_[k]), "vkResetFences");
        check(vkResetCommandBuffer(commands_[k], 0), "vkResetCommandBuffer");
        VkCommandBufferBeginInfo info{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
        info.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
        check(vkBeginCommandBuffer(commands_[k], &info), "vkBeginCommandBuffer");
        return commands_[k];
    }
    /// Ends and submits the frame's command buffer with its fence; does not wait.
    void submit(uint64_t frame) {
        const size_t k = frame % commands_.size();
        check(vkEndCommandBuffer(commands_[k]), "vkEndCommandBuffer");
        VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
        submit.commandBufferCount = 1;
        submit.pCommandBuffers = &commands_[k];
        check(vkQueueSubmit(queue_, 1, &submit, fences_[k]), "vkQueueSubmit");
    }
    /// Waits for frame `frame` (its slot's fence).
    void wait(uint64_t frame) {
        const size_t k = frame % commands_.size();
        check(vkWaitForFences(device_, 1, &fences_[k], VK_TRUE, UINT64_MAX), "vkWaitForFences");
    }
    void wait_all() {
        check(vkWaitForFences(device_, uint32_t(fences_.size()), fences_.data(), VK_TRUE, UINT64_MAX), "vkWaitForFences");
    }

private:
    VkDevice device_;
    VkQueue queue_;
    VkCommandPool pool_ = VK_NULL_HANDLE;
    std::vector<VkCommandBuffer> commands_;
    std::vector<VkFence> fences_;
};

/// A buffer in host-visible, coherent memory, mapped for its lifetime.
class HostBuffer {
public:
    HostBuffer(const Device& device, VkDeviceSize size, VkBufferUsageFlags usage) : device_(device.handle()), size_(size) {
        VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
        info.size = size;
        info.usage = usage;
        check(vkCreateBuffer(device_, &info, nullptr, &buffer_), "vkCreateBuffer");
        VkMemoryRequirements needs;
        vkGetBufferMemoryRequirements(device_, buffer_, &needs);
        VkMemoryAllocateInfo allocate{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
        allocate.allocationSize = needs.size;
        allocate.memoryTypeIndex = device.memory_type(
            needs.memoryTypeBits, VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT);
        check(vkAllocateMemory(device_, &allocate, nullptr, &memory_), "vkAllocateMemory");
        check(vkBindBufferMemory(device_, buffer_, memory_, 0), "vkBindBufferMemory");
        check(vkMapMemory(device_, memory_, 0, VK_WHOLE_SIZE, 0, &mapped_), "vkMapMemory");
    }
    ~HostBuffer() {
        vkDestroyBuffer(device_, buffer_, nullptr);
        vkFreeMemory(device_, memory_, nullptr);
    }
    HostBuffer(const HostBuffer&) = delete;
    HostBuffer& operator=(const HostBuffer&) = delete;

    VkBuffer handle() const { return buffer_; }
    VkDeviceSize size() const { return size_; }
    template <class T> T* data() const { return static_cast<T*>(mapped_); }

private:
    VkDevice device_;
    VkDeviceSize size_;
    VkBuffer buffer_ = VK_NULL_HANDLE;
    VkDeviceMemory memory_ = VK_NULL_HANDLE;
    void* mapped_ = nullptr;
};

}  // namespace engine
