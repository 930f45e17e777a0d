// The walk that integrates ahead, decided by the step layer (src/step_program.h AheadSchedule)
// and run through the CUDA kernel bodies on the host (tests/agreement/cuda_emulation_backend.h):
// no GPU needed.
#include "simulation_access.h"
#include "cuda_emulation_backend.h"
#include "cuda_test_support.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

namespace hmsm::cuda_test {
namespace {

// Stepped call by call with live changes in between (the wind, a force field, an instance's wind
// scale, one paused and resumed, one added, a field moved before every call for a while) and one
// call of many steps, a simulation whose backend integrates ahead leaves the same joint matrices
// and angles, bit for bit, as one whose backend does not. It takes the angles integrated ahead
// where nothing changed, and walks plain while the field moves before every call. Calls of
// several steps run the walk ahead at wind-table slots past the first, where the atmospheric
// profile's walk ahead must read the slot after its own step's. Under the coupled dynamics the
// walk ahead also reads this step's loads and writes the next step's.
struct AheadCase {
    WindProfile profile;
    Dynamics dynamics;
};
constexpr LiveScript kScript{.wind = 4, .field = 8, .scale = 10, .pause = 12, .resume = 14, .add = 16,
                             .moving_from = 22, .moving_to = 40, .long_call = 20, .long_steps = 12};

class CudaEmulationAheadSchedule : public ::testing::TestWithParam<AheadCase> {};

TEST_P(CudaEmulationAheadSchedule, StepLayerDecidesFromLiveChangesBitForBit) {
    const Scene scene = forest_scene(7);
    SimulationConfig config = test_config(BackendKind::cuda, Composition::path_walk, false);
    config.wind.profile = GetParam().profile;
    config.wind.turbulence = 0.9;
    config.model.dynamics = GetParam().dynamics;
    test::EmulatedAheadSteps steps;
    auto plain = detail::SimulationAccess::create(scene, config, test::create_cuda_emulation_backend());
    auto ahead = detail::SimulationAccess::create(scene, config, test::create_cuda_emulation_backend(&steps));
    ASSERT_TRUE(plain.ok() && ahead.ok());
    bool walked_ahead = false;
    uint64_t taken_before_calm = 0, plain_before_field = 0;
    for (uint32_t k = 0; k < 44; ++k) {
        if (k == 22) plain_before_field = steps.plain;
        if (k == 40) taken_before_calm = steps.taken;
        for (Simulation* sim : {plain->get(), ahead->get()}) {
            run_live_call(*sim, scene, kScript, k);
            if (HasFatalFailure()) return;
        }
        const auto& program = detail::step_program_of(**ahead);
        walked_ahead = walked_ahead || std::any_of(program.begin(), program.end(), detail::is_walk_ahead);
        for (Output output : {Output::joint_matrices, Output::chain_angles}) {
            std::vector<double> expected, actual;
            ASSERT_TRUE((*plain)->read(output, expected).ok());
            ASSERT_TRUE((*ahead)->read(output, actual).ok());
            ASSERT_EQ(actual, expected) << "output " << int(output) << " after call " << k;
        }
    }
    EXPECT_TRUE(walked_ahead);
    EXPECT_GE(steps.taken, 20u);
    // The moving field (17 calls, each after a change): all but the first two and every eighth
    // walked plain; after it, the walk ahead again.
    EXPECT_GE(steps.plain - plain_before_field, 12u);
    EXPECT_GE(steps.taken - taken_before_calm, 2u);
}

INSTANTIATE_TEST_SUITE_P(Profiles, CudaEmulationAheadSchedule,
                         ::testing::Values(AheadCase{WindProfile::y1, Dynamics::paper},
                                           AheadCase{WindProfile::atmospheric, Dynamics::paper},
                                           AheadCase{WindProfile::y1, Dynamics::coupled},
                                           AheadCase{WindProfile::atmospheric, Dynamics::coupled}),
                         [](const auto& info) {
                             return std::string(to_string(info.param.profile)) + "_" + to_string(info.param.dynamics);
                         });

}  // namespace
}  // namespace hmsm::cuda_test
