#include "vulkan_test_support.h"

#include "engine_device.h"

#include <hmsm/vulkan.h>

#include "vulkan/validation.h"

#include <cmath>
#include <limits>
#include <mutex>

namespace hmsm::test {
namespace {

struct Messages {
    std::mutex mutex;
    std::vector<std::string> list;
    bool enabled = false;
};
Messages& messages() {
    static Messages m;
    return m;
}

}  // namespace

bool install_vulkan_validation() {
    if (!detail::vulkan_validation_layer_available()) return false;
    detail::vulkan_set_validation(true, [](const std::string& message) {
        std::lock_guard lock(messages().mutex);
        messages().list.push_back(message);
    });
    messages().enabled = true;
    return true;
}

bool vulkan_validation_enabled() { return messages().enabled; }

std::vector<std::string> take_validation_messages() {
    std::lock_guard lock(messages().mutex);
    return std::exchange(messages().list, {});
}

std::unique_ptr<detail::Backend> create_vulkan_or_skip(std::string& skip) {
    auto backend = detail::create_vulkan_backend();
    if (!backend.ok()) {
        if (backend.status().code() == ErrorCode::no_device) skip = backend.status().message();
        else ADD_FAILURE() << backend.status().message();
        return nullptr;
    }
    return std::move(backend).value();
}

std::vector<double> read_buffer(const detail::Backend& backend, detail::BufferId id, uint64_t count) {
    std::vector<double> values(count * detail::shape_scalars(detail::buffer_info(id).shape));
    Status s = backend.read(id, 0, count, values.data(), detail::Scalar::f64);
    EXPECT_TRUE(s.ok()) << s.message();
    return values;
}

double relative_difference(const std::vector<double>& a, const std::vector<double>& b) {
    if (a.size() != b.size()) return std::numeric_limits<double>::infinity();
    double scale = 1.0, diff = 0.0;
    for (size_t i = 0; i < a.size(); ++i) {
        if (!std::isfinite(a[i]) || !std::isfinite(b[i])) return std::numeric_limits<double>::infinity();
        scale = std::max(scale, std::abs(b[i]));
        diff = std::max(diff, std::abs(a[i] - b[i]));
    }
    return diff / scale;
}

void add_validation_message(const std::string& message) {
    std::lock_guard lock(messages().mutex);
    messages().list.push_back(message);
}

}  // namespace hmsm::test
