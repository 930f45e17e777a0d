// Batched launches through the CUDA kernel bodies on the host: the emulation backend
// (tests/agreement/cuda_emulation_backend.h) runs each batch block by block through the entry
// search the kernels use (src/common/batch_index.h). A scene of many groups steps bit for bit
// as dispatch by dispatch, in every composition and the walk ahead, in both vertex layouts, with
// grids capped (every entry striding over its elements) or not, and follows cpu64. Needs no GPU;
// cuda_batch_test.cpp checks the same on the device.
#include "simulation_access.h"
#include "cuda_emulation_backend.h"
#include "cuda_test_support.h"
#include "test_compositions.h"

#include "cuda/launch_plan.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>

namespace hmsm::cuda_test {
namespace {

struct BatchCase {
    test::TestComposition composition;
    uint32_t max_blocks;  // the batches' grid cap
    VertexLayout layout;
};

class CudaEmulationBatches : public ::testing::TestWithParam<BatchCase> {};

TEST_P(CudaEmulationBatches, ManyGroupsStepBitForBitAsSingleLaunches) {
    const BatchCase c = GetParam();
    const Scene scene = many_groups_scene(5, 13);
    SimulationConfig config = test_config(BackendKind::cuda, c.composition.composition, false);
    config.vertex_layout = c.layout;
    test::EmulatedAheadSteps single_steps, batched_steps;
    auto single = detail::SimulationAccess::create(scene, config, test::create_cuda_emulation_backend(&single_steps, false),
                                                   c.composition.jumping_form);
    auto batched = detail::SimulationAccess::create(
        scene, config, test::create_cuda_emulation_backend(&batched_steps, true, c.max_blocks), c.composition.jumping_form);
    SimulationConfig reference_config = config;
    reference_config.backend = BackendKind::cpu64;
    auto reference = test::create_simulation(scene, reference_config, c.composition);
    ASSERT_TRUE(single.ok() && batched.ok() && reference.ok());
    expect_batches_match_single_launches(**single, **batched, **reference);
    if (HasFatalFailure()) return;
    // The step ran batches of many entries.
    const auto& program = detail::step_program_of(**batched);
    const detail::cuda::LaunchPlan plan = detail::cuda::plan_launches(program, true, c.max_blocks);
    EXPECT_LT(plan.launches.size() * 4, program.size());
    EXPECT_TRUE(std::any_of(plan.launches.begin(), plan.launches.end(),
                            [](const detail::cuda::PlannedLaunch& launch) { return launch.entries >= 6; }));
    if (c.composition.composition == Composition::path_walk) {
        EXPECT_GT(batched_steps.taken, 0u);  // the walk ahead ran and its angles were taken
        EXPECT_EQ(batched_steps.taken, single_steps.taken);
    }
}

INSTANTIATE_TEST_SUITE_P(
    Compositions, CudaEmulationBatches,
    ::testing::Values(BatchCase{Composition::pointer_jumping, 1u << 16, VertexLayout::separate},
                      BatchCase{test::kJumpingPerRound, 3, VertexLayout::separate},
                      BatchCase{test::kJumpingInDispatch, 3, VertexLayout::packed},
                      BatchCase{Composition::level_by_level, 3, VertexLayout::separate},
                      BatchCase{Composition::path_walk, 1u << 16, VertexLayout::separate},
                      BatchCase{Composition::path_walk, 3, VertexLayout::packed}),
    [](const auto& info) {
        return test::name_of(info.param.composition) + "_" + to_string(info.param.layout) +
               (info.param.max_blocks < 16 ? "_capped" : "");
    });

}  // namespace
}  // namespace hmsm::cuda_test
