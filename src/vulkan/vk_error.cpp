#include "vk_error.h"

#include <cstring>
#include <string>

namespace hmsm::detail::vk {

const char* result_name(VkResult result) {
    switch (result) {
#define HMSM_VK_RESULT(name) case name: return #name;
        HMSM_VK_RESULT(VK_SUCCESS)
        HMSM_VK_RESULT(VK_NOT_READY)
        HMSM_VK_RESULT(VK_TIMEOUT)
        HMSM_VK_RESULT(VK_EVENT_SET)
        HMSM_VK_RESULT(VK_EVENT_RESET)
        HMSM_VK_RESULT(VK_INCOMPLETE)
        HMSM_VK_RESULT(VK_ERROR_OUT_OF_HOST_MEMORY)
        HMSM_VK_RESULT(VK_ERROR_OUT_OF_DEVICE_MEMORY)
        HMSM_VK_RESULT(VK_ERROR_INITIALIZATION_FAILED)
        HMSM_VK_RESULT(VK_ERROR_DEVICE_LOST)
        HMSM_VK_RESULT(VK_ERROR_MEMORY_MAP_FAILED)
        HMSM_VK_RESULT(VK_ERROR_LAYER_NOT_PRESENT)
        HMSM_VK_RESULT(VK_ERROR_EXTENSION_NOT_PRESENT)
        HMSM_VK_RESULT(VK_ERROR_FEATURE_NOT_PRESENT)
        HMSM_VK_RESULT(VK_ERROR_INCOMPATIBLE_DRIVER)
        HMSM_VK_RESULT(VK_ERROR_TOO_MANY_OBJECTS)
        HMSM_VK_RESULT(VK_ERROR_FORMAT_NOT_SUPPORTED)
        HMSM_VK_RESULT(VK_ERROR_FRAGMENTED_POOL)
        HMSM_VK_RESULT(VK_ERROR_UNKNOWN)
        HMSM_VK_RESULT(VK_ERROR_OUT_OF_POOL_MEMORY)
        HMSM_VK_RESULT(VK_ERROR_INVALID_EXTERNAL_HANDLE)
        HMSM_VK_RESULT(VK_ERROR_FRAGMENTATION)
        HMSM_VK_RESULT(VK_ERROR_INVALID_OPAQUE_CAPTURE_ADDRESS)
        HMSM_VK_RESULT(VK_PIPELINE_COMPILE_REQUIRED)
        HMSM_VK_RESULT(VK_ERROR_VALIDATION_FAILED_EXT)
#undef HMSM_VK_RESULT
        default: return nullptr;
    }
}

Status failure(VkResult result, const char* expression, const char* file, int line) {
    const char* name = result_name(result);
    std::string code = name ? name : "VkResult(" + std::to_string(int(result)) + ")";
    const char* base = std::strrchr(file, '/');
    std::string message = "vulkan: " + std::string(expression) + " failed with " + code + " (" +
                          (base ? base + 1 : file) + ":" + std::to_string(line) + ")";
    switch (result) {
        case VK_ERROR_OUT_OF_HOST_MEMORY:
        case VK_ERROR_OUT_OF_DEVICE_MEMORY:
            return {ErrorCode::out_of_memory, std::move(message)};
        case VK_ERROR_INITIALIZATION_FAILED:
        case VK_ERROR_INCOMPATIBLE_DRIVER:
            return {ErrorCode::no_device, std::move(message)};
        default:
            return {ErrorCode::device_error, std::move(message)};
    }
}

}  // namespace hmsm::detail::vk
