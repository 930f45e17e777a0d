// Switches Vulkan validation on for instances hmsm creates from now on (tests, debugging).
// Validation means VK_LAYER_KHRONOS_validation with synchronization validation and a debug-utils
// messenger for warnings and errors. Setting the environment variable HMSM_VULKAN_VALIDATION=1
// has the same effect. While validation is on, a backend operation during which the layer
// reported anything fails with ErrorCode::internal and the first message, so any test that
// drives the backend fails on a validation message without further harness code.
#pragma once

#include <functional>
#include <string>

namespace hmsm::detail {

/// Called for every validation message (any thread), in addition to the failing Status.
using VulkanValidationCallback = std::function<void(const std::string& message)>;

/// Turns validation on or off for instances created afterwards; `callback` may be empty.
void vulkan_set_validation(bool enabled, VulkanValidationCallback callback = {});
/// True when VK_LAYER_KHRONOS_validation is installed (false also when no loader exists).
bool vulkan_validation_layer_available();

}  // namespace hmsm::detail
