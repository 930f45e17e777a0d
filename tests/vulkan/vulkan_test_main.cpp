// The Vulkan tests' main: turns validation (with synchronization validation) on before any
// instance exists, so every backend the tests create is validated.
#include "vulkan_test_support.h"

#include <cstdio>
#include <cstdlib>

int main(int argc, char** argv) {
    ::testing::InitGoogleTest(&argc, argv);
    if (!hmsm::test::install_vulkan_validation()) {
        const char* require = std::getenv("HMSM_VULKAN_REQUIRE_VALIDATION");
        if (require && std::string(require) == "1") {
            std::fprintf(stderr, "VK_LAYER_KHRONOS_validation is not installed "
                                 "(HMSM_VULKAN_REQUIRE_VALIDATION=1)\n");
            return 1;
        }
        std::fprintf(stderr, "note: VK_LAYER_KHRONOS_validation is not installed; the Vulkan "
                             "tests run without validation\n");
    }
    return RUN_ALL_TESTS();
}
