// Batched launches on the device (src/cuda/launch_plan.h): a scene of many groups (instances
// alternating between two models and their levels of detail, no size a multiple of the block
// size) steps bit for bit as with HMSM_CUDA_BATCH_RUNS=0 (one launch per dispatch), in every
// composition, the walk ahead and the plain walk, graph replay and profiled launches, and
// agrees with cpu64. Every test skips with the reason when there is no CUDA device
// (batch_emulation_test.cpp runs the same batches on the host).
#include "simulation_access.h"
#include "cuda_test_support.h"
#include "test_compositions.h"

#include "cuda/cuda_backend.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

namespace hmsm::cuda_test {
namespace {

struct DeviceBatchCase {
    test::TestComposition composition;
    bool walk_ahead;  // HMSM_CUDA_WALK_AHEAD (path walk)
    bool profile;     // launches one by one between events instead of the graph
    VertexLayout layout;
};

std::unique_ptr<Simulation> create_with(const Scene& scene, const SimulationConfig& config,
                                        const DeviceBatchCase& c, bool batch_runs) {
    if (!batch_runs) setenv("HMSM_CUDA_BATCH_RUNS", "0", 1);
    if (!c.walk_ahead) setenv("HMSM_CUDA_WALK_AHEAD", "0", 1);
    auto sim = detail::SimulationAccess::create(scene, config, c.composition.jumping_form);
    unsetenv("HMSM_CUDA_BATCH_RUNS");
    unsetenv("HMSM_CUDA_WALK_AHEAD");
    EXPECT_TRUE(sim.ok()) << sim.status().message();
    return sim.ok() ? std::move(sim).value() : nullptr;
}

class CudaBatches : public ::testing::TestWithParam<DeviceBatchCase> {};

TEST_P(CudaBatches, ManyGroupsStepBitForBitAsSingleLaunchesAndFollowCpu64) {
    HMSM_SKIP_WITHOUT_CUDA();
    const DeviceBatchCase c = GetParam();
    const Scene scene = many_groups_scene(9, 301);
    SimulationConfig config = test_config(BackendKind::cuda, c.composition.composition, c.profile);
    config.vertex_layout = c.layout;
    auto single = create_with(scene, config, c, false);
    auto batched = create_with(scene, config, c, true);
    SimulationConfig reference_config = config;
    reference_config.backend = BackendKind::cpu64;
    reference_config.profile_passes = false;
    auto reference = test::create_simulation(scene, reference_config, c.composition);
    ASSERT_TRUE(single && batched && reference.ok());
    expect_batches_match_single_launches(*single, *batched, **reference);
    if (HasFatalFailure()) return;
    const auto& backend = dynamic_cast<const detail::cuda::CudaBackend&>(detail::backend_of(*batched));
    if (c.composition.composition == Composition::path_walk && c.walk_ahead && !c.profile)
        EXPECT_GT(backend.steps_taken_ahead(), 0u);
}

INSTANTIATE_TEST_SUITE_P(
    Compositions, CudaBatches,
    ::testing::Values(DeviceBatchCase{Composition::pointer_jumping, true, false, VertexLayout::separate},
                      DeviceBatchCase{test::kJumpingPerRound, true, false, VertexLayout::separate},
                      DeviceBatchCase{test::kJumpingInDispatch, true, false, VertexLayout::packed},
                      DeviceBatchCase{Composition::level_by_level, true, false, VertexLayout::separate},
                      DeviceBatchCase{Composition::path_walk, true, false, VertexLayout::separate},
                      DeviceBatchCase{Composition::path_walk, true, false, VertexLayout::packed},
                      DeviceBatchCase{Composition::path_walk, false, false, VertexLayout::separate},
                      DeviceBatchCase{Composition::path_walk, true, true, VertexLayout::separate},
                      DeviceBatchCase{test::kJumpingInDispatch, true, true, VertexLayout::separate}),
    [](const auto& info) {
        const DeviceBatchCase& c = info.param;
        return test::name_of(c.composition) + "_" + to_string(c.layout) + (c.walk_ahead ? "" : "_no_walk_ahead") +
               (c.profile ? "_profiled" : "");
    });

}  // namespace
}  // namespace hmsm::cuda_test
