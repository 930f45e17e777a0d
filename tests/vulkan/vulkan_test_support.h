// Shared by the Vulkan tests: a fixture that fails a test on any validation message reported
// while it ran, and helpers that skip when there is no Vulkan device.
#pragma once

#include "backend.h"
#include "vulkan/vulkan_backend.h"

#include <hmsm/hmsm.h>
#include <hmsm/vulkan.h>

#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

namespace hmsm::test {

/// Installs the validation callback (vulkan_test_main.cpp); true when validation is on.
bool install_vulkan_validation();
bool vulkan_validation_enabled();
/// Validation messages since the last call, cleared.
std::vector<std::string> take_validation_messages();

class VulkanTest : public ::testing::Test {
protected:
    void SetUp() override { take_validation_messages(); }
    void TearDown() override {
        auto messages = take_validation_messages();
        EXPECT_TRUE(messages.empty()) << messages.size() << " validation message(s), first: "
                                      << messages.front();
    }
};

/// A Vulkan backend, or null with `skip` set to the reason (no device); other errors fail.
std::unique_ptr<detail::Backend> create_vulkan_or_skip(std::string& skip);

/// Reads a whole buffer as doubles.
std::vector<double> read_buffer(const detail::Backend& backend, detail::BufferId id, uint64_t count);
/// max |a - b| / max(1, max |b|); infinity when sizes differ or anything is NaN.
double relative_difference(const std::vector<double>& a, const std::vector<double>& b);

}  // namespace hmsm::test
