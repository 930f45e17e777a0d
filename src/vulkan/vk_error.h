// VkResult -> Status. Every Vulkan call that can fail goes through HMSM_VK_TRY, which keeps the
// expression, file and line in the message; nothing in the Vulkan backend aborts or throws.
#pragma once

#include <hmsm/status.h>

#include "volk_private.h"

namespace hmsm::detail::vk {

/// "VK_ERROR_DEVICE_LOST" etc.; "VkResult(<n>)" for codes this build does not know.
const char* result_name(VkResult result);

/// The Status for a failed call: out_of_memory for the two out-of-memory codes, no_device for
/// a missing driver or loader, device_error otherwise.
Status failure(VkResult result, const char* expression, const char* file, int line);

}  // namespace hmsm::detail::vk

/// Returns a Status (convertible to Result<T>) from the enclosing function when `expr` does not
/// give VK_SUCCESS.
#define HMSM_VK_TRY(expr)                                                              \
    do {                                                                               \
        VkResult hmsm_vk_result_ = (expr);                                             \
        if (hmsm_vk_result_ != VK_SUCCESS)                                             \
            return ::hmsm::detail::vk::failure(hmsm_vk_result_, #expr, __FILE__, __LINE__); \
    } while (0)
