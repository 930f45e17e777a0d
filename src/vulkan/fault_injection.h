// Test hook: makes Vulkan backends created afterwards fail the way a real device does, so the
// error paths (out of device memory at upload, device lost mid-run and for good) can be tested
// where the real failure cannot be provoked. Off unless a test turns it on.
#pragma once

#include <cstdint>

namespace hmsm::detail {

enum class VulkanFault {
    none,
    out_of_device_memory_at_upload,  ///< upload() fails as vkAllocateMemory would
    device_lost_at_submit,           ///< the (after+1)-th submission fails; the device stays lost
    out_of_device_memory_at_growth,  ///< grow() fails as vkAllocateMemory would
};

/// Applies to backends created after the call; `after` successful submissions come first.
void vulkan_inject_fault(VulkanFault fault, uint32_t after = 0);

}  // namespace hmsm::detail
