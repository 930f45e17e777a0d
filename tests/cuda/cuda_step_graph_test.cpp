// Step graphs on the device (src/cuda/step_graph.h, cuda_backend.h): a named program's first
// step is launched directly and its second captured; programs that change every frame (a tree
// streamed out and in each frame) step bit for bit as with HMSM_CUDA_CAPTURE_AT_ONCE=1, also
// enqueued back to back on an engine stream, where each new program's launch table goes up
// while the steps before still run. Every test skips with the reason when there is no device.
#include "simulation_access.h"
#include "cuda_test_support.h"
#include "test_trees.h"

#include "cuda/cuda_backend.h"

#include <hmsm/cuda.h>

#include <cuda_runtime_api.h>

#include <cstdlib>
#include <cstring>

namespace hmsm::cuda_test {
namespace {

std::unique_ptr<Simulation> create_with(const Scene& scene, const SimulationConfig& config, bool walk_ahead,
                                        bool capture_at_once) {
    if (!walk_ahead) setenv("HMSM_CUDA_WALK_AHEAD", "0", 1);
    if (capture_at_once) setenv("HMSM_CUDA_CAPTURE_AT_ONCE", "1", 1);
    auto sim = Simulation::create(scene, config);
    unsetenv("HMSM_CUDA_WALK_AHEAD");
    unsetenv("HMSM_CUDA_CAPTURE_AT_ONCE");
    EXPECT_TRUE(sim.ok()) << sim.status().message();
    return sim.ok() ? std::move(sim).value() : nullptr;
}

const detail::cuda::CudaBackend& cuda_backend_of(const Simulation& sim) {
    return dynamic_cast<const detail::cuda::CudaBackend&>(detail::backend_of(sim));
}

/// Streams instance 0 out and back in (it goes last): the step program changes.
Status restream_first(Simulation& sim) {
    const Instance moved = sim.instances()[0];
    const uint64_t first = 0;
    HMSM_TRY(sim.remove_instances({&first, 1}));
    return sim.add_instances({&moved, 1});
}

TEST(CudaStepGraphs, ANamedProgramIsLaunchedOnItsFirstStepAndCapturedOnItsSecond) {
    HMSM_SKIP_WITHOUT_CUDA();
    const Scene scene = forest_scene(31);
    auto sim = create_with(scene, test_config(BackendKind::cuda, Composition::path_walk, false), false, false);
    ASSERT_TRUE(sim);
    const auto& backend = cuda_backend_of(*sim);
    for (int change = 0; change < 3; ++change) {
        SCOPED_TRACE(change);
        if (change > 0) ASSERT_TRUE(restream_first(*sim).ok());
        const uint64_t captured = backend.graphs_captured();
        const uint64_t launched = backend.steps_launched();
        ASSERT_TRUE(sim->step(1).ok());
        EXPECT_EQ(backend.graphs_captured(), captured);
        EXPECT_GT(backend.steps_launched(), launched);
        const uint64_t launched_first = backend.steps_launched();
        ASSERT_TRUE(sim->step(1).ok());
        EXPECT_EQ(backend.graphs_captured(), captured + 1);
        ASSERT_TRUE(sim->step(5).ok());
        EXPECT_EQ(backend.graphs_captured(), captured + 1);
        EXPECT_EQ(backend.steps_launched(), launched_first);
    }
    // Captured on the first step where asked to.
    auto at_once = create_with(scene, test_config(BackendKind::cuda, Composition::path_walk, false), false, true);
    ASSERT_TRUE(at_once);
    const uint64_t captured = cuda_backend_of(*at_once).graphs_captured();
    ASSERT_TRUE(at_once->step(1).ok());
    EXPECT_EQ(cuda_backend_of(*at_once).graphs_captured(), captured + 1);
}

TEST(CudaStepGraphs, ProgramsThatChangeEveryFrameStepAsCapturedAtOnceBitForBit) {
    HMSM_SKIP_WITHOUT_CUDA();
    for (Composition composition : {Composition::path_walk, Composition::pointer_jumping}) {
        SCOPED_TRACE(to_string(composition));
        const Scene scene = many_groups_scene(32, 37);
        const SimulationConfig config = test_config(BackendKind::cuda, composition, false);
        auto at_once = create_with(scene, config, true, true);
        auto enqueued = create_with(scene, config, true, false);
        ASSERT_TRUE(at_once && enqueued);
        cudaStream_t stream = nullptr;
        ASSERT_EQ(cudaStreamCreateWithFlags(&stream, cudaStreamNonBlocking), cudaSuccess);
        const uint64_t launched = cuda_backend_of(*enqueued).steps_launched();
        // A new program every frame, its first step launched from a new table while the frame
        // before may still run on the stream; every third frame a second step, captured.
        for (uint32_t k = 0; k < 30; ++k) {
            ASSERT_TRUE(restream_first(*at_once).ok());
            ASSERT_TRUE(restream_first(*enqueued).ok());
            const uint64_t steps = k % 3 == 0 ? 2 : 1;
            ASSERT_TRUE(at_once->step(steps).ok());
            ASSERT_TRUE(cuda::enqueue_steps(*enqueued, stream, steps).ok());
        }
        EXPECT_GE(cuda_backend_of(*enqueued).steps_launched() - launched, 30u);
        ASSERT_EQ(enqueued->steps_done(), at_once->steps_done());
        for (Output o : test::kEveryOutput) {
            std::vector<float> a, b;
            ASSERT_TRUE(at_once->read(o, a).ok());
            ASSERT_TRUE(enqueued->read(o, b).ok());
            ASSERT_EQ(a.size(), b.size());
            ASSERT_FALSE(a.empty());
            EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(float)), 0) << "output " << int(o);
        }
        ASSERT_TRUE(cuda::set_stream(*enqueued, nullptr).ok());
        EXPECT_EQ(cudaStreamDestroy(stream), cudaSuccess);
    }
}

}  // namespace
}  // namespace hmsm::cuda_test
