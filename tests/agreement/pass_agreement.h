// The per-pass agreement suite's shared parts (pass_agreement_test.cpp runs it): which
// backends it runs on, and its one tolerance rule. Every backend runs each dispatch of each
// pass alone on the same random states (random_scene.h) as the cpu64 oracle.
#pragma once

#include "backend.h"
#include "random_scene.h"

#include <hmsm/pass.h>
#include <hmsm/simulation.h>

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace hmsm::test {

/// A backend the suite checks: its name in test names and its factory. A factory that returns
/// no_device (not compiled in, no device) makes the backend's tests skip with its message.
struct BackendUnderTest {
    std::string name;
    std::function<Result<std::unique_ptr<detail::Backend>>()> create;
};

/// Every backend of the suite (pass_agreement.cpp; adding a backend is one line there).
const std::vector<BackendUnderTest>& backends_under_test();

/// Normalized mean squared error of `actual` against the oracle's `expected` (ggml's
/// test-backend-ops): sum (actual - expected)^2 / sum expected^2. Infinity when either holds
/// a NaN or the sizes differ; 0 for two all-zero arrays.
double nmse(const std::vector<double>& expected, const std::vector<double>& actual);

/// The one tolerance: a float backend against the double oracle on one pass of random states.
/// It is docs/model.md 7's relative bound of 1e-4, squared. Float rounding alone gives 1e-15 to
/// 1e-13, and wind_force 5e-11 (its float wind phase f t + phi is rounded before the profile
/// amplifies it); a wrong index or operand moves whole elements, about 1 / (elements) or more.
inline constexpr double kMaxPassNmse = 1e-8;

/// The forms a pass is checked under: one for a flat pass (its dispatches do not
/// depend on it); every round alone, every round in one dispatch and level by level for
/// compose and root_positions.
std::vector<PassForm> forms_of(Pass pass);

}  // namespace hmsm::test
