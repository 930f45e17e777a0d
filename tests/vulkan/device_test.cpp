// Device choice (HMSM_VULKAN_DEVICE), error reporting, `auto` selection and the validation
// harness itself.
#include "vulkan_test_support.h"

#include "vulkan/device.h"
#include "vulkan/vk_error.h"

#include <cctype>
#include <cstdlib>
#include <optional>

namespace hmsm::test {
namespace {

/// Sets an environment variable for the scope, restoring the previous value.
class ScopedEnv {
public:
    ScopedEnv(const char* name, const char* value) : name_(name) {
        if (const char* old = std::getenv(name)) previous_ = old;
        setenv(name, value, 1);
    }
    ~ScopedEnv() {
        if (previous_) setenv(name_, previous_->c_str(), 1);
        else unsetenv(name_);
    }

private:
    const char* name_;
    std::optional<std::string> previous_;
};

/// The name of the device hmsm picks by default, or empty with `skip` set.
std::string default_device_name(std::string& skip) {
    auto backend = create_vulkan_or_skip(skip);
    return backend ? backend->device_name() : std::string();
}

TEST_F(VulkanTest, DeviceOverrideByIndexAndByName) {
    std::string skip;
    const std::string name = default_device_name(skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    {
        ScopedEnv env("HMSM_VULKAN_DEVICE", "0");
        auto backend = detail::create_vulkan_backend();
        ASSERT_TRUE(backend.ok()) << backend.status().message();
    }
    // A case-changed substring of the name selects the same device.
    std::string key = name.substr(0, std::min<size_t>(name.size(), 6));
    for (char& c : key) c = char(std::isupper(static_cast<unsigned char>(c)) ? std::tolower(c) : std::toupper(c));
    ScopedEnv env("HMSM_VULKAN_DEVICE", key.c_str());
    auto backend = detail::create_vulkan_backend();
    ASSERT_TRUE(backend.ok()) << backend.status().message();
    EXPECT_EQ(backend.value()->device_name(), name);
}

TEST_F(VulkanTest, DeviceOverrideWithoutMatchIsAClearError) {
    std::string skip;
    const std::string name = default_device_name(skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    for (const char* wanted : {"no-such-gpu-xyz", "97"}) {
        ScopedEnv env("HMSM_VULKAN_DEVICE", wanted);
        auto backend = detail::create_vulkan_backend();
        ASSERT_FALSE(backend.ok());
        EXPECT_EQ(backend.status().code(), ErrorCode::no_device);
        const std::string message = backend.status().message();
        EXPECT_NE(message.find("HMSM_VULKAN_DEVICE"), std::string::npos) << message;
        EXPECT_NE(message.find(wanted), std::string::npos) << message;
        EXPECT_NE(message.find(name), std::string::npos) << "lists the devices: " << message;
    }
}

TEST_F(VulkanTest, NoDriverGivesNoDeviceNotACrash) {
    ScopedEnv icd("VK_ICD_FILENAMES", "/nonexistent/hmsm_no_icd.json");
    ScopedEnv drivers("VK_DRIVER_FILES", "/nonexistent/hmsm_no_icd.json");
    auto backend = detail::create_vulkan_backend();
    ASSERT_FALSE(backend.ok());
    EXPECT_EQ(backend.status().code(), ErrorCode::no_device) << backend.status().message();
    // The loader may warn about the missing driver file through the validation messenger.
    take_validation_messages();
}

TEST_F(VulkanTest, AutomaticPrefersAGpuOverACpuDriver) {
    std::string skip;
    auto vulkan = create_vulkan_or_skip(skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    auto chosen = detail::create_backend(BackendKind::automatic);
    ASSERT_TRUE(chosen.ok());
    if (detail::vulkan_backend_is_cpu_device(*vulkan)) {
        EXPECT_NE(chosen.value()->kind(), BackendKind::vulkan) << "picked " << vulkan->device_name();
    } else {
        EXPECT_NE(chosen.value()->kind(), BackendKind::cpu) << "a GPU exists: " << vulkan->device_name();
    }
}

TEST(VulkanErrors, StatusNamesTheVkResultExpressionAndLine) {
    Status lost = detail::vk::failure(VK_ERROR_DEVICE_LOST, "vkQueueSubmit(q, 1, &s, f)", "/a/b/file.cpp", 42);
    EXPECT_EQ(lost.code(), ErrorCode::device_error);
    EXPECT_NE(lost.message().find("VK_ERROR_DEVICE_LOST"), std::string::npos);
    EXPECT_NE(lost.message().find("vkQueueSubmit(q, 1, &s, f)"), std::string::npos);
    EXPECT_NE(lost.message().find("file.cpp:42"), std::string::npos);
    EXPECT_EQ(detail::vk::failure(VK_ERROR_OUT_OF_DEVICE_MEMORY, "x", "f", 1).code(), ErrorCode::out_of_memory);
    EXPECT_EQ(detail::vk::failure(VK_ERROR_INCOMPATIBLE_DRIVER, "x", "f", 1).code(), ErrorCode::no_device);
    EXPECT_NE(detail::vk::failure(VkResult(-12345), "x", "f", 1).message().find("VkResult(-12345)"),
              std::string::npos);
}

TEST_F(VulkanTest, ValidationHarnessCatchesAnInvalidCall) {
    if (!vulkan_validation_enabled()) GTEST_SKIP() << "VK_LAYER_KHRONOS_validation is not installed";
    auto device = detail::vk::Device::create();
    if (!device.ok() && device.status().code() == ErrorCode::no_device) GTEST_SKIP() << device.status().message();
    ASSERT_TRUE(device.ok()) << device.status().message();
    const detail::vk::Device& d = *device.value();
    VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    info.size = 0;  // invalid: VUID-VkBufferCreateInfo-size-00912
    info.usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
    VkBuffer buffer = VK_NULL_HANDLE;
    d.vk().vkCreateBuffer(d.handle(), &info, nullptr, &buffer);
    if (buffer) d.vk().vkDestroyBuffer(d.handle(), buffer, nullptr);
    EXPECT_FALSE(take_validation_messages().empty()) << "the harness callback saw nothing";
    Status s = device.value()->take_validation_messages();
    EXPECT_EQ(s.code(), ErrorCode::internal);
    EXPECT_NE(s.message().find("VUID-VkBufferCreateInfo-size"), std::string::npos) << s.message();
}

}  // namespace
}  // namespace hmsm::test
