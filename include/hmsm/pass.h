// The seven passes of one step (docs/model.md 2, 3.7). The same names are used for the CPU sources
// (src/cpu/NAME.cpp), the shaders (shaders/glsl/NAME.comp) and the kernels (kernels/cuda/NAME.cu).
#pragma once

#include <hmsm/export.h>

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>

namespace hmsm {

/// X(name): every pass in execution order.
#define HMSM_PASSES(X) \
    X(wind_force)      \
    X(integrate)       \
    X(compose)         \
    X(node_relative)   \
    X(root_positions)  \
    X(node_world)      \
    X(contour)

enum class Pass : uint32_t {
#define HMSM_PASS_ENUM(name) name,
    HMSM_PASSES(HMSM_PASS_ENUM)
#undef HMSM_PASS_ENUM
};

inline constexpr uint32_t kPassCount = 0
#define HMSM_PASS_COUNT(name) +1
    HMSM_PASSES(HMSM_PASS_COUNT)
#undef HMSM_PASS_COUNT
    ;

inline constexpr std::array<Pass, kPassCount> kAllPasses = {
#define HMSM_PASS_LIST(name) Pass::name,
    HMSM_PASSES(HMSM_PASS_LIST)
#undef HMSM_PASS_LIST
};

constexpr std::string_view pass_name(Pass pass) {
    constexpr std::array<std::string_view, kPassCount> names = {
#define HMSM_PASS_NAME(name) #name,
        HMSM_PASSES(HMSM_PASS_NAME)
#undef HMSM_PASS_NAME
    };
    return names[static_cast<uint32_t>(pass)];
}

HMSM_API std::optional<Pass> parse_pass(std::string_view name);

/// Device time per pass (seconds, summed over every step of the last Simulation::step call) and
/// the number of steps it covers. All zero when the backend was not asked to profile.
struct PassTimes {
    std::array<double, kPassCount> seconds{};
    uint64_t steps = 0;
    double total() const {
        double sum = 0.0;
        for (double s : seconds) sum += s;
        return sum;
    }
};

}  // namespace hmsm
