#include "device.h"

#include "validation.h"
#include "vk_error.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace hmsm::detail {
namespace {

struct ValidationSettings {
    std::mutex mutex;
    bool enabled = false;
    VulkanValidationCallback callback;
};
ValidationSettings& validation_settings() {
    static ValidationSettings settings;
    return settings;
}

bool validation_requested() {
    ValidationSettings& s = validation_settings();
    std::lock_guard lock(s.mutex);
    if (s.enabled) return true;
    const char* env = std::getenv("HMSM_VULKAN_VALIDATION");
    return env && (std::strcmp(env, "1") == 0 || std::strcmp(env, "on") == 0 ||
                   std::strcmp(env, "true") == 0);
}

constexpr const char* kValidationLayer = "VK_LAYER_KHRONOS_validation";

/// Guards volk's global (instance-level) function pointers, hmsm's private copies
/// (src/vulkan/volk_private.h).
std::mutex& loader_mutex() {
    static std::mutex mutex;
    return mutex;
}
bool system_loader_loaded = false;     // volkInitialize() done (and not replaced by a custom one)
bool system_instance_loaded = false;   // instance-level pointers loaded through the system loader

/// Loads the Vulkan loader (or the engine's entry point) into volk's global function pointers.
Status load_loader(PFN_vkGetInstanceProcAddr custom) {
    std::lock_guard lock(loader_mutex());
    if (custom) {
        volkInitializeCustom(custom);
        system_loader_loaded = system_instance_loaded = false;
        return {};
    }
    if (system_loader_loaded) return {};
    if (volkInitialize() != VK_SUCCESS)
        return {ErrorCode::no_device, "vulkan: no Vulkan loader (libvulkan.so.1) on this system"};
    system_loader_loaded = true;
    return {};
}

/// Loads volk's instance-level pointers from `instance`. Through the system loader they are
/// the loader's trampolines, the same for every instance, so they are loaded once and never
/// rewritten while other threads call through them: simulations may be created and destroyed
/// from several threads at once. An engine's own entry point
/// (ExternalContext::get_instance_proc_addr) reloads them for each adopted device.
void load_instance_functions(VkInstance instance, bool custom) {
    std::lock_guard lock(loader_mutex());
    if (!custom && system_instance_loaded) return;
    volkLoadInstanceOnly(instance);
    system_instance_loaded = !custom;
}

bool layer_present(const char* name) {
    uint32_t count = 0;
    if (vkEnumerateInstanceLayerProperties(&count, nullptr) != VK_SUCCESS) return false;
    std::vector<VkLayerProperties> layers(count);
    if (vkEnumerateInstanceLayerProperties(&count, layers.data()) != VK_SUCCESS) return false;
    return std::any_of(layers.begin(), layers.end(),
                       [&](const VkLayerProperties& l) { return std::strcmp(l.layerName, name) == 0; });
}

std::string lowercase(std::string s) {
    for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

const char* type_name(VkPhysicalDeviceType type) {
    switch (type) {
        case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return "discrete GPU";
        case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return "integrated GPU";
        case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return "virtual GPU";
        case VK_PHYSICAL_DEVICE_TYPE_CPU: return "CPU";
        default: return "other";
    }
}

/// Lower is preferred: discrete, integrated, virtual, other, CPU.
int type_rank(VkPhysicalDeviceType type) {
    switch (type) {
        case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return 0;
        case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return 1;
        case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return 2;
        case VK_PHYSICAL_DEVICE_TYPE_CPU: return 4;
        default: return 3;
    }
}

/// A compute queue family, preferring one with timestamps; -1 when there is none.
int compute_queue_family(VkPhysicalDevice physical) {
    uint32_t count = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(physical, &count, nullptr);
    std::vector<VkQueueFamilyProperties> families(count);
    vkGetPhysicalDeviceQueueFamilyProperties(physical, &count, families.data());
    int best = -1;
    for (uint32_t i = 0; i < count; ++i) {
        if (!(families[i].queueFlags & VK_QUEUE_COMPUTE_BIT) || families[i].queueCount == 0) continue;
        if (best < 0 || (families[best].timestampValidBits == 0 && families[i].timestampValidBits > 0))
            best = int(i);
    }
    return best;
}

}  // namespace

void vulkan_set_validation(bool enabled, VulkanValidationCallback callback) {
    ValidationSettings& s = validation_settings();
    std::lock_guard lock(s.mutex);
    s.enabled = enabled;
    s.callback = std::move(callback);
}

bool vulkan_validation_layer_available() {
    return load_loader(nullptr).ok() && layer_present(kValidationLayer);
}

namespace vk {

Result<std::shared_ptr<Device>> Device::create() {
    HMSM_TRY(load_loader(nullptr));
    std::shared_ptr<Device> device(new Device());
    HMSM_TRY(device->create_instance());
    HMSM_TRY(device->choose_physical_device());
    HMSM_TRY(device->create_device());
    HMSM_TRY(device->load_device_info());
    return device;
}

Result<std::shared_ptr<Device>> Device::adopt(const hmsm::vulkan::ExternalContext& context) {
    if (!context.instance || !context.physical_device || !context.device || !context.queue)
        return Status{ErrorCode::invalid_argument,
                      "vulkan: ExternalContext needs instance, physical_device, device and queue"};
    HMSM_TRY(load_loader(context.get_instance_proc_addr));
    load_instance_functions(context.instance, context.get_instance_proc_addr != nullptr);
    std::shared_ptr<Device> device(new Device());
    device->owned_ = false;
    device->instance_ = context.instance;
    device->physical_ = context.physical_device;
    device->device_ = context.device;
    device->queue_ = context.queue;
    device->queue_family_ = context.queue_family_index;

    VkPhysicalDeviceProperties properties;
    vkGetPhysicalDeviceProperties(context.physical_device, &properties);
    if (properties.apiVersion < VK_API_VERSION_1_1)
        return Status{ErrorCode::unsupported,
                      "vulkan: the engine's device " + std::string(properties.deviceName) +
                          " supports Vulkan " + std::to_string(VK_API_VERSION_MAJOR(properties.apiVersion)) +
                          "." + std::to_string(VK_API_VERSION_MINOR(properties.apiVersion)) +
                          "; hmsm needs 1.1"};
    uint32_t count = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(context.physical_device, &count, nullptr);
    std::vector<VkQueueFamilyProperties> families(count);
    vkGetPhysicalDeviceQueueFamilyProperties(context.physical_device, &count, families.data());
    if (context.queue_family_index >= count ||
        !(families[context.queue_family_index].queueFlags & VK_QUEUE_COMPUTE_BIT))
        return Status{ErrorCode::invalid_argument,
                      "vulkan: ExternalContext.queue_family_index " +
                          std::to_string(context.queue_family_index) + " has no compute support"};
    volkLoadDeviceTable(&device->table_, context.device);
    HMSM_TRY(device->load_device_info());
    return device;
}

Device::~Device() {
    if (!owned_ || abandoned_) return;
    if (device_) {
        table_.vkDeviceWaitIdle(device_);
        table_.vkDestroyDevice(device_, nullptr);
    }
    if (messenger_ && destroy_messenger_) destroy_messenger_(instance_, messenger_, nullptr);
    if (instance_) vkDestroyInstance(instance_, nullptr);
}

Status Device::create_instance() {
    VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
    app.pApplicationName = "hmsm";
    app.pEngineName = "hmsm";
    app.apiVersion = VK_API_VERSION_1_1;

    VkInstanceCreateInfo info{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
    info.pApplicationInfo = &app;

    const bool validate = validation_requested();
    const char* layers[] = {kValidationLayer};
    const char* extensions[] = {VK_EXT_DEBUG_UTILS_EXTENSION_NAME,
                                VK_EXT_VALIDATION_FEATURES_EXTENSION_NAME};
    // Synchronization validation finds missing or wrong barriers between our dispatches.
    VkValidationFeatureEnableEXT enables[] = {VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT};
    VkValidationFeaturesEXT features{VK_STRUCTURE_TYPE_VALIDATION_FEATURES_EXT};
    features.enabledValidationFeatureCount = 1;
    features.pEnabledValidationFeatures = enables;
    VkDebugUtilsMessengerCreateInfoEXT messenger{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
    messenger.pNext = &features;
    messenger.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT |
                                VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
    messenger.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT |
                            VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                            VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
    messenger.pfnUserCallback = &Device::on_message;
    messenger.pUserData = this;
    if (validate) {
        if (!layer_present(kValidationLayer))
            return {ErrorCode::no_device,
                    "vulkan: validation was requested (HMSM_VULKAN_VALIDATION or "
                    "vulkan_set_validation) but VK_LAYER_KHRONOS_validation is not installed"};
        info.enabledLayerCount = 1;
        info.ppEnabledLayerNames = layers;
        info.enabledExtensionCount = 2;
        info.ppEnabledExtensionNames = extensions;
        info.pNext = &messenger;  // also reports during vkCreateInstance / vkDestroyInstance
    }
    HMSM_VK_TRY(vkCreateInstance(&info, nullptr, &instance_));
    load_instance_functions(instance_, false);
    if (validate) {
        // Extension entry points are fetched per instance: the loader returns them only for an
        // instance that enabled the extension.
        auto create = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
            vkGetInstanceProcAddr(instance_, "vkCreateDebugUtilsMessengerEXT"));
        destroy_messenger_ = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
            vkGetInstanceProcAddr(instance_, "vkDestroyDebugUtilsMessengerEXT"));
        if (!create || !destroy_messenger_)
            return {ErrorCode::device_error, "vulkan: VK_EXT_debug_utils entry points missing"};
        messenger.pNext = nullptr;
        HMSM_VK_TRY(create(instance_, &messenger, nullptr, &messenger_));
    }
    return {};
}

Status Device::choose_physical_device() {
    uint32_t count = 0;
    HMSM_VK_TRY(vkEnumeratePhysicalDevices(instance_, &count, nullptr));
    std::vector<VkPhysicalDevice> devices(count);
    HMSM_VK_TRY(vkEnumeratePhysicalDevices(instance_, &count, devices.data()));
    if (count == 0) return {ErrorCode::no_device, "vulkan: no Vulkan device found"};

    struct Candidate {
        VkPhysicalDevice physical;
        VkPhysicalDeviceProperties properties;
        int queue_family;
        std::string unusable;  // why hmsm cannot run on it; empty when it can
    };
    std::vector<Candidate> candidates;
    std::string listing;
    for (uint32_t i = 0; i < count; ++i) {
        Candidate c{devices[i], {}, compute_queue_family(devices[i]), {}};
        vkGetPhysicalDeviceProperties(devices[i], &c.properties);
        if (c.queue_family < 0) c.unusable = "no compute queue";
        else if (c.properties.apiVersion < VK_API_VERSION_1_1) c.unusable = "Vulkan 1.0 only";
        listing += (i ? ", " : "") + std::to_string(i) + ": " + c.properties.deviceName + " (" +
                   type_name(c.properties.deviceType) + ")";
        candidates.push_back(std::move(c));
    }

    const Candidate* chosen = nullptr;
    if (const char* wanted = std::getenv("HMSM_VULKAN_DEVICE"); wanted && *wanted) {
        std::string key = wanted;
        bool is_index = std::all_of(key.begin(), key.end(), [](char ch) { return std::isdigit(
                                                                          static_cast<unsigned char>(ch)); });
        if (is_index) {
            unsigned long index = std::strtoul(key.c_str(), nullptr, 10);
            if (index < candidates.size()) chosen = &candidates[index];
        } else {
            for (const Candidate& c : candidates)
                if (lowercase(c.properties.deviceName).find(lowercase(key)) != std::string::npos) {
                    chosen = &c;
                    break;
                }
        }
        if (!chosen)
            return {ErrorCode::no_device, "vulkan: HMSM_VULKAN_DEVICE='" + key +
                                              "' matches no device; devices: " + listing};
        if (!chosen->unusable.empty())
            return {ErrorCode::no_device, "vulkan: HMSM_VULKAN_DEVICE='" + key + "' selects " +
                                              chosen->properties.deviceName +
                                              ", which hmsm cannot use: " + chosen->unusable};
    } else {
        for (const Candidate& c : candidates) {
            if (!c.unusable.empty()) continue;
            if (!chosen || type_rank(c.properties.deviceType) < type_rank(chosen->properties.deviceType))
                chosen = &c;
        }
        if (!chosen)
            return {ErrorCode::no_device, "vulkan: no device with a compute queue and Vulkan 1.1; devices: " +
                                              listing};
    }
    physical_ = chosen->physical;
    queue_family_ = uint32_t(chosen->queue_family);
    return {};
}

Status Device::create_device() {
    const float priority = 1.0f;
    VkDeviceQueueCreateInfo queue{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
    queue.queueFamilyIndex = queue_family_;
    queue.queueCount = 1;
    queue.pQueuePriorities = &priority;
    VkDeviceCreateInfo info{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
    info.queueCreateInfoCount = 1;
    info.pQueueCreateInfos = &queue;
    HMSM_VK_TRY(vkCreateDevice(physical_, &info, nullptr, &device_));
    volkLoadDeviceTable(&table_, device_);
    table_.vkGetDeviceQueue(device_, queue_family_, 0, &queue_);
    return {};
}

Status Device::load_device_info() {
    VkPhysicalDeviceMaintenance3Properties maintenance3{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_MAINTENANCE_3_PROPERTIES};
    VkPhysicalDeviceProperties2 properties2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2};
    properties2.pNext = &maintenance3;
    vkGetPhysicalDeviceProperties2(physical_, &properties2);
    properties_ = properties2.properties;
    vkGetPhysicalDeviceMemoryProperties(physical_, &memory_);

    const VkPhysicalDeviceLimits& l = properties_.limits;
    limits_.max_storage_buffer_range = l.maxStorageBufferRange;
    limits_.max_memory_allocation_size = maintenance3.maxMemoryAllocationSize;
    limits_.min_storage_buffer_offset_alignment = std::max<VkDeviceSize>(1, l.minStorageBufferOffsetAlignment);
    for (int i = 0; i < 3; ++i) limits_.max_workgroup_count[i] = l.maxComputeWorkGroupCount[i];
    limits_.max_workgroup_size_x = l.maxComputeWorkGroupSize[0];
    limits_.max_workgroup_invocations = l.maxComputeWorkGroupInvocations;
    limits_.max_shared_memory_bytes = l.maxComputeSharedMemorySize;
    limits_.max_push_constants_size = l.maxPushConstantsSize;
    limits_.max_storage_buffers_per_stage = l.maxPerStageDescriptorStorageBuffers;
    limits_.max_storage_buffers_per_set = l.maxDescriptorSetStorageBuffers;

    uint32_t count = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(physical_, &count, nullptr);
    std::vector<VkQueueFamilyProperties> families(count);
    vkGetPhysicalDeviceQueueFamilyProperties(physical_, &count, families.data());
    limits_.timestamp_valid_bits = queue_family_ < count ? families[queue_family_].timestampValidBits : 0;
    limits_.timestamp_period_ns = limits_.timestamp_valid_bits ? double(l.timestampPeriod) : 0.0;
    return {};
}

Status Device::take_validation_messages() {
    std::lock_guard lock(messages_mutex_);
    if (messages_.empty()) return {};
    std::string first = messages_.front();
    size_t more = messages_.size() - 1;
    messages_.clear();
    return {ErrorCode::internal, "vulkan validation: " + first +
                                     (more ? " (and " + std::to_string(more) + " more)" : "")};
}

VkBool32 VKAPI_PTR Device::on_message(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                      VkDebugUtilsMessageTypeFlagsEXT,
                                      const VkDebugUtilsMessengerCallbackDataEXT* data, void* user) {
    std::string message = std::string(severity & VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT
                                          ? "error: "
                                          : "warning: ") +
                          (data && data->pMessage ? data->pMessage : "(no message)");
    auto* device = static_cast<Device*>(user);
    {
        std::lock_guard lock(device->messages_mutex_);
        device->messages_.push_back(message);
    }
    ValidationSettings& s = validation_settings();
    VulkanValidationCallback callback;
    {
        std::lock_guard lock(s.mutex);
        callback = s.callback;
    }
    if (callback) callback(message);
    else std::fprintf(stderr, "hmsm: vulkan validation %s\n", message.c_str());
    return VK_FALSE;
}

}  // namespace vk
}  // namespace hmsm::detail
