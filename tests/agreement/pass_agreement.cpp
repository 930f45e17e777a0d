#include "pass_agreement.h"

#ifdef HMSM_HAVE_CUDA
#include "cuda_emulation_backend.h"
#endif

#include <cmath>
#include <limits>

namespace hmsm::test {
namespace {

Result<std::unique_ptr<detail::Backend>> cuda_emulation() {
#ifdef HMSM_HAVE_CUDA
    return create_cuda_emulation_backend();
#else
    return Status{ErrorCode::no_device, "cuda emulation: this build of hmsm has no CUDA kernels"};
#endif
}

template <BackendKind kKind>
Result<std::unique_ptr<detail::Backend>> registered() {
    return detail::create_backend(kKind);
}

}  // namespace

const std::vector<BackendUnderTest>& backends_under_test() {
    static const std::vector<BackendUnderTest> backends = {
        {"cpu", registered<BackendKind::cpu>},
        {"vulkan", registered<BackendKind::vulkan>},
        {"cuda", registered<BackendKind::cuda>},
        {"cuda_emulation", cuda_emulation},
    };
    return backends;
}

double nmse(const std::vector<double>& expected, const std::vector<double>& actual) {
    constexpr double kInfinity = std::numeric_limits<double>::infinity();
    if (expected.size() != actual.size()) return kInfinity;
    double error = 0.0, norm = 0.0;
    for (size_t i = 0; i < expected.size(); ++i) {
        if (std::isnan(expected[i]) || std::isnan(actual[i])) return kInfinity;
        const double d = actual[i] - expected[i];
        error += d * d;
        norm += expected[i] * expected[i];
    }
    if (norm == 0.0) return error == 0.0 ? 0.0 : kInfinity;
    return error / norm;
}

std::vector<PassForm> forms_of(Pass pass) {
    // A path-walk dispatch of a pass that leads one also runs its walk partner.
    if (pass == Pass::wind_force || pass == Pass::node_relative) return {PassForm::jump_per_round, PassForm::path_walk};
    if (pass == Pass::compose)
        return {PassForm::jump_per_round, PassForm::jump_in_dispatch, PassForm::level_by_level, PassForm::path_walk};
    if (pass == Pass::root_positions)
        return {PassForm::jump_per_round, PassForm::jump_in_dispatch, PassForm::level_by_level};
    return {PassForm::jump_per_round};
}

}  // namespace hmsm::test
