// An engine that links the system Vulkan loader (Vulkan::Vulkan) and calls it directly, before
// and after running hmsm. With volk's globals exported from hmsm, vkCreateInstance here would
// resolve to hmsm's (null) function pointer and crash.
#include "consumer_common.h"

#include <vulkan/vulkan.h>

#include <cstdlib>

static int engine_vulkan(const char* when) {
    VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
    app.apiVersion = VK_API_VERSION_1_1;
    VkInstanceCreateInfo info{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
    info.pApplicationInfo = &app;
    VkInstance instance = VK_NULL_HANDLE;
    const VkResult result = vkCreateInstance(&info, nullptr, &instance);
    if (result != VK_SUCCESS) {
        std::fprintf(stderr, "engine (%s): vkCreateInstance failed (%d)\n", when, int(result));
        return 1;
    }
    uint32_t count = 0;
    vkEnumeratePhysicalDevices(instance, &count, nullptr);
    std::printf("engine (%s): its own instance sees %u device(s)\n", when, count);
    vkDestroyInstance(instance, nullptr);
    return 0;
}

int main() {
    if (engine_vulkan("before hmsm") != 0) return 1;
    if (run_both() != 0) return 1;
    return engine_vulkan("after hmsm");
}
