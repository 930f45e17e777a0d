// An engine that brings its own volk (compiled into the program, global vk* pointers) and
// loads it before running hmsm; both volks must keep their own tables.
#include "consumer_common.h"

#include <volk.h>

static int engine_vulkan(const char* when) {
    VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
    app.apiVersion = VK_API_VERSION_1_1;
    VkInstanceCreateInfo info{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
    info.pApplicationInfo = &app;
    VkInstance instance = VK_NULL_HANDLE;
    if (vkCreateInstance(&info, nullptr, &instance) != VK_SUCCESS) {
        std::fprintf(stderr, "engine (%s): vkCreateInstance failed\n", when);
        return 1;
    }
    volkLoadInstance(instance);
    uint32_t count = 0;
    vkEnumeratePhysicalDevices(instance, &count, nullptr);
    std::printf("engine (%s): its own volk sees %u device(s)\n", when, count);
    vkDestroyInstance(instance, nullptr);
    return 0;
}

int main() {
    if (volkInitialize() != VK_SUCCESS) {
        std::fprintf(stderr, "engine: no Vulkan loader\n");
        return 1;
    }
    if (engine_vulkan("before hmsm") != 0) return 1;
    if (run_both() != 0) return 1;
    return engine_vulkan("after hmsm");
}
