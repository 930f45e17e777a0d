// The CUDA backend on a device: whole simulations against the double-precision CPU reference,
// graph replay against direct launches, profiling, interop and error paths (each pass on random
// states is agreement/pass_agreement_test.cpp). Every test skips with the reason when there is
// no CUDA device.
#include "simulation_access.h"
#include "cuda_test_support.h"
#include "test_compositions.h"

#include <hmsm/cuda.h>

#include "common/octahedral.h"
#include "cuda/cuda_backend.h"

#include <cuda_runtime_api.h>
#include <algorithm>

#include <cmath>
#include <cstdlib>
#include <cstring>

namespace hmsm::cuda_test {
namespace {

using detail::BufferId;
using detail::Scalar;

std::unique_ptr<Simulation> create_or_fail(const Scene& scene, const SimulationConfig& config,
                                           detail::JumpingForm jumping_form = detail::JumpingForm::by_size) {
    auto sim = detail::SimulationAccess::create(scene, config, jumping_form);
    EXPECT_TRUE(sim.ok()) << sim.status().message();
    return sim.ok() ? std::move(sim).value() : nullptr;
}

// --- no device ---------------------------------------------------------------------------

TEST(CudaNoDevice, CreatingTheBackendReportsNoDevice) {
    if (no_cuda_device_reason().empty()) GTEST_SKIP() << "a CUDA device is present";
    auto backend = detail::create_backend(BackendKind::cuda);
    ASSERT_FALSE(backend.ok());
    EXPECT_EQ(backend.status().code(), ErrorCode::no_device);
    EXPECT_NE(backend.status().message().find("no CUDA device is available"), std::string::npos);
    auto sim = Simulation::create(forest_scene(1), test_config(BackendKind::cuda, Composition::pointer_jumping, false));
    ASSERT_FALSE(sim.ok());
    EXPECT_EQ(sim.status().code(), ErrorCode::no_device);
}

// --- whole simulations -------------------------------------------------------------------

void expect_agreement(const Scene& scene, test::TestComposition composition, bool profile,
                      std::initializer_list<uint32_t> step_calls) {
    auto reference = create_or_fail(scene, test_config(BackendKind::cpu64, composition.composition, false),
                                    composition.jumping_form);
    auto device = create_or_fail(scene, test_config(BackendKind::cuda, composition.composition, profile),
                                 composition.jumping_form);
    ASSERT_TRUE(reference && device);
    for (uint32_t steps : step_calls) {
        ASSERT_TRUE(reference->step(steps).ok());
        const Status status = device->step(steps);
        ASSERT_TRUE(status.ok()) << status.message();
    }
    const double height = scene_height(scene);
    for (Output output : {Output::node_positions, Output::vertex_positions, Output::vertex_normals,
                          Output::chain_origins}) {
        std::vector<double> expected, actual;
        ASSERT_TRUE(reference->read(output, expected).ok());
        ASSERT_TRUE(device->read(output, actual).ok());
        // Positions: docs/model.md 7's bound, relative to the tree height. Normals are unit vectors
        // renormalized after the fix-up blend, which amplifies rounding where the own and the
        // parent normal nearly cancel: the serial float path is 2.4e-4 off cpu64 on the preset
        // forest, so they get a looser absolute bound.
        const bool normals = output == Output::vertex_normals;
        EXPECT_LE(max_abs_difference(actual, expected) / (normals ? 1.0 : height), normals ? 1e-3 : 1e-4)
            << "output " << int(output);
    }
}

// The walk that integrates ahead (forests on CUDA): stepped call by call with live changes in
// between (run_live_call) and one call of many steps, a simulation that takes the angles
// integrated ahead leaves the same joint matrices and angles, bit for bit, as one whose backend
// does not integrate ahead, and it does take them; under y1 and under the atmospheric profile,
// whose walk ahead evaluates the wind of the slot after its step's itself; under either dynamics.
class CudaWalkAhead : public ::testing::TestWithParam<std::pair<WindProfile, Dynamics>> {};

TEST_P(CudaWalkAhead, StepByStepWithLiveChangesEqualsThePlainWalkBitForBit) {
    HMSM_SKIP_WITHOUT_CUDA();
    const Scene scene = forest_scene(7);
    SimulationConfig config = test_config(BackendKind::cuda, Composition::path_walk, false);
    config.wind.profile = GetParam().first;
    config.wind.turbulence = 0.9;
    config.model.dynamics = GetParam().second;
    const LiveScript script{.wind = 8, .field = 16, .scale = 20, .pause = 24, .resume = 30, .add = 36,
                            .moving_from = 40, .moving_to = 56, .long_call = 40, .long_steps = 300};
    setenv("HMSM_CUDA_WALK_AHEAD", "0", 1);
    auto plain = create_or_fail(scene, config);
    unsetenv("HMSM_CUDA_WALK_AHEAD");
    auto ahead = create_or_fail(scene, config);
    ASSERT_TRUE(plain && ahead);
    const auto& backend = dynamic_cast<const detail::cuda::CudaBackend&>(hmsm::detail::backend_of(*ahead));
    bool walked_ahead = false;
    uint64_t taken_before_calm = 0;
    for (uint32_t k = 0; k < 60; ++k) {
        if (k == 56) taken_before_calm = backend.steps_taken_ahead();
        // One call of 300 steps runs in two chunks of the wind table (Simulation::step), the
        // second taking the first's angles.
        for (Simulation* sim : {plain.get(), ahead.get()}) {
            run_live_call(*sim, scene, script, k);
            if (HasFatalFailure()) return;
        }
        const auto& program = hmsm::detail::step_program_of(*ahead);
        walked_ahead = walked_ahead || std::any_of(program.begin(), program.end(), detail::is_walk_ahead);
        for (Output output : {Output::joint_matrices, Output::chain_angles}) {
            std::vector<double> expected, actual;
            ASSERT_TRUE(plain->read(output, expected).ok());
            ASSERT_TRUE(ahead->read(output, actual).ok());
            ASSERT_EQ(actual, expected) << "output " << int(output) << " after call " << k;
        }
    }
    EXPECT_TRUE(walked_ahead);
    EXPECT_GE(backend.steps_taken_ahead(), 320u);
    // The moving field: most of those calls walked plain; after it, the walk ahead again.
    EXPECT_GE(backend.steps_walked_plain(), 10u);
    EXPECT_GE(backend.steps_taken_ahead() - taken_before_calm, 3u);
}

INSTANTIATE_TEST_SUITE_P(Profiles, CudaWalkAhead,
                         ::testing::Values(std::pair{WindProfile::y1, Dynamics::paper},
                                           std::pair{WindProfile::atmospheric, Dynamics::paper},
                                           std::pair{WindProfile::y1, Dynamics::coupled},
                                           std::pair{WindProfile::atmospheric, Dynamics::coupled}),
                         [](const auto& info) {
                             return std::string(to_string(info.param.first)) + "_" + to_string(info.param.second);
                         });

class CudaSimulation : public ::testing::TestWithParam<test::TestComposition> {};

TEST_P(CudaSimulation, ForestAgreesWithCpu64AfterManySteps) {
    HMSM_SKIP_WITHOUT_CUDA();
    expect_agreement(forest_scene(7), GetParam(), false, {100, 1, 139});
}

TEST_P(CudaSimulation, ProfiledForestAgreesWithCpu64) {
    HMSM_SKIP_WITHOUT_CUDA();
    expect_agreement(forest_scene(8), GetParam(), true, {60, 60});
}

TEST_P(CudaSimulation, PresetForestAgreesWithCpu64) {
    HMSM_SKIP_WITHOUT_CUDA();
    auto tree = generate_preset("paper-5");
    ASSERT_TRUE(tree.ok()) << tree.status().message();
    auto scene = grid_scene(*tree, 37, 12.0, 3);
    ASSERT_TRUE(scene.ok()) << scene.status().message();
    expect_agreement(*scene, GetParam(), false, {30});
}

INSTANTIATE_TEST_SUITE_P(Compositions, CudaSimulation,
                         ::testing::Values(test::kJumpingPerRound, test::kJumpingInDispatch,
                                           test::TestComposition(Composition::level_by_level),
                                           test::TestComposition(Composition::path_walk)),
                         [](const auto& info) { return test::name_of(info.param); });

TEST(CudaGraph, ReplayEqualsDirectLaunchesBitwise) {
    HMSM_SKIP_WITHOUT_CUDA();
    const Scene scene = forest_scene(9);
    auto graph = create_or_fail(scene, test_config(BackendKind::cuda, Composition::pointer_jumping, false));
    auto direct = create_or_fail(scene, test_config(BackendKind::cuda, Composition::pointer_jumping, true));
    ASSERT_TRUE(graph && direct);
    for (uint32_t steps : {1u, 50u, 49u}) {
        ASSERT_TRUE(graph->step(steps).ok());
        ASSERT_TRUE(direct->step(steps).ok());
    }
    for (Output output : {Output::node_positions, Output::vertex_positions, Output::vertex_normals,
                          Output::chain_rotations, Output::chain_angles}) {
        std::vector<float> a, b;
        ASSERT_TRUE(graph->read(output, a).ok());
        ASSERT_TRUE(direct->read(output, b).ok());
        ASSERT_EQ(a.size(), b.size());
        EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(float)), 0) << "output " << int(output);
    }
}

TEST(CudaProfiling, PassTimesAreReportedOnlyWhenProfiling) {
    HMSM_SKIP_WITHOUT_CUDA();
    const Scene scene = forest_scene(10);
    auto profiled = create_or_fail(scene, test_config(BackendKind::cuda, Composition::pointer_jumping, true));
    auto plain = create_or_fail(scene, test_config(BackendKind::cuda, Composition::pointer_jumping, false));
    ASSERT_TRUE(profiled && plain);
    ASSERT_TRUE(profiled->step(20).ok());
    ASSERT_TRUE(plain->step(20).ok());
    const PassTimes times = profiled->pass_times();
    EXPECT_EQ(times.steps, 20u);
    for (Pass pass : kAllPasses) EXPECT_GT(times.seconds[uint32_t(pass)], 0.0) << pass_name(pass);
    EXPECT_EQ(plain->pass_times().total(), 0.0);
    EXPECT_EQ(plain->pass_times().steps, 0u);
}

// --- interop -----------------------------------------------------------------------------

TEST(CudaInterop, DeviceOutputsHoldWhatReadReturns) {
    HMSM_SKIP_WITHOUT_CUDA();
    const Scene scene = forest_scene(12);
    auto sim = create_or_fail(scene, test_config(BackendKind::cuda, Composition::pointer_jumping, false));
    ASSERT_TRUE(sim);
    ASSERT_TRUE(sim->step(10).ok());
    auto outputs = cuda::device_outputs(*sim);
    ASSERT_TRUE(outputs.ok()) << outputs.status().message();
    EXPECT_EQ(outputs->node_count, sim->node_count());
    EXPECT_EQ(outputs->vertex_count, sim->vertex_count());
    struct Check {
        const float* device;
        uint64_t count;
        Output output;
        float w;
    };
    for (Check check : {Check{outputs->node_positions, outputs->node_count, Output::node_positions, 1.0f},
                        Check{outputs->vertex_positions, outputs->vertex_count, Output::vertex_positions, 1.0f},
                        Check{outputs->vertex_normals, outputs->vertex_count, Output::vertex_normals, 0.0f}}) {
        std::vector<float> raw(check.count * 4), expected;
        ASSERT_EQ(cudaMemcpy(raw.data(), check.device, raw.size() * sizeof(float), cudaMemcpyDeviceToHost), cudaSuccess);
        ASSERT_TRUE(sim->read(check.output, expected).ok());
        for (uint64_t i = 0; i < check.count; ++i) {
            for (int k = 0; k < 3; ++k) ASSERT_EQ(raw[4 * i + k], expected[3 * i + k]) << "element " << i;
            ASSERT_EQ(raw[4 * i + 3], check.w);
        }
    }
}

TEST(CudaInterop, PackedLayoutHasNoNormalBufferAndNormalWordsInW) {
    HMSM_SKIP_WITHOUT_CUDA();
    const Scene scene = forest_scene(16);
    SimulationConfig config = test_config(BackendKind::cuda, Composition::pointer_jumping, false);
    config.vertex_layout = VertexLayout::packed;
    auto sim = create_or_fail(scene, config);
    ASSERT_TRUE(sim);
    ASSERT_TRUE(sim->step(10).ok());
    auto outputs = cuda::device_outputs(*sim);
    ASSERT_TRUE(outputs.ok()) << outputs.status().message();
    EXPECT_EQ(outputs->vertex_layout, VertexLayout::packed);
    EXPECT_EQ(outputs->vertex_normals, nullptr);
    ASSERT_NE(outputs->vertex_positions, nullptr);
    std::vector<float> raw(outputs->vertex_count * 4), positions, normals;
    ASSERT_EQ(cudaMemcpy(raw.data(), outputs->vertex_positions, raw.size() * sizeof(float), cudaMemcpyDeviceToHost),
              cudaSuccess);
    ASSERT_TRUE(sim->read(Output::vertex_positions, positions).ok());
    ASSERT_TRUE(sim->read(Output::vertex_normals, normals).ok());
    for (uint64_t i = 0; i < outputs->vertex_count; ++i) {
        for (int k = 0; k < 3; ++k) ASSERT_EQ(raw[4 * i + k], positions[3 * i + k]) << "vertex " << i;
        const auto n = detail::decode_normal_word<float>(detail::bits_from_float(raw[4 * i + 3]));
        ASSERT_EQ(n.x, normals[3 * i]) << "vertex " << i;
        ASSERT_EQ(n.y, normals[3 * i + 1]) << "vertex " << i;
        ASSERT_EQ(n.z, normals[3 * i + 2]) << "vertex " << i;
    }
    // The separate layout of the same scene: the same positions, normals within quantization.
    auto separate = create_or_fail(scene, test_config(BackendKind::cuda, Composition::pointer_jumping, false));
    ASSERT_TRUE(separate);
    ASSERT_TRUE(separate->step(10).ok());
    std::vector<float> separate_positions, separate_normals;
    ASSERT_TRUE(separate->read(Output::vertex_positions, separate_positions).ok());
    ASSERT_TRUE(separate->read(Output::vertex_normals, separate_normals).ok());
    EXPECT_EQ(positions, separate_positions);
    double worst = 0.0;
    for (size_t i = 0; i < normals.size(); ++i) worst = std::max(worst, double(std::abs(normals[i] - separate_normals[i])));
    EXPECT_LE(worst, 1e-4);
}

TEST(CudaInterop, StepsRunOnAnEngineStream) {
    HMSM_SKIP_WITHOUT_CUDA();
    const Scene scene = forest_scene(13);
    auto engine = create_or_fail(scene, test_config(BackendKind::cuda, Composition::pointer_jumping, false));
    auto own = create_or_fail(scene, test_config(BackendKind::cuda, Composition::pointer_jumping, false));
    ASSERT_TRUE(engine && own);
    cudaStream_t stream = nullptr;
    ASSERT_EQ(cudaStreamCreate(&stream), cudaSuccess);
    ASSERT_TRUE(cuda::set_stream(*engine, stream).ok());
    ASSERT_TRUE(engine->step(25).ok());
    ASSERT_TRUE(cuda::set_stream(*engine, nullptr).ok());
    ASSERT_TRUE(engine->step(5).ok());
    ASSERT_TRUE(own->step(30).ok());
    std::vector<float> a, b;
    ASSERT_TRUE(engine->read(Output::vertex_positions, a).ok());
    ASSERT_TRUE(own->read(Output::vertex_positions, b).ok());
    EXPECT_EQ(a, b);
    EXPECT_EQ(cudaStreamDestroy(stream), cudaSuccess);
}

TEST(CudaInterop, OtherBackendsHaveNoDeviceOutputs) {
    auto sim = create_or_fail(forest_scene(14), test_config(BackendKind::cpu, Composition::pointer_jumping, false));
    ASSERT_TRUE(sim);
    auto outputs = cuda::device_outputs(*sim);
    ASSERT_FALSE(outputs.ok());
    EXPECT_EQ(outputs.status().code(), ErrorCode::invalid_argument);
}

// --- errors ------------------------------------------------------------------------------

TEST(CudaErrors, OutOfMemoryNamesTheBufferAndKeepsTheDeviceUsable) {
    HMSM_SKIP_WITHOUT_CUDA();
    auto backend = detail::create_backend(BackendKind::cuda);
    ASSERT_TRUE(backend.ok());
    size_t free_bytes = 0, total_bytes = 0;
    ASSERT_EQ(cudaMemGetInfo(&free_bytes, &total_bytes), cudaSuccess);
    detail::SceneData huge;  // a "forest" whose vertex positions alone exceed device memory
    huge.total_vertices = huge.vertex_capacity = total_bytes / 16 + (1ull << 24);
    const Status status = (*backend)->upload(huge);
    EXPECT_EQ(status.code(), ErrorCode::out_of_memory) << status.message();
    EXPECT_NE(status.message().find("vertex_position"), std::string::npos) << status.message();
    EXPECT_NE(status.message().find("bytes"), std::string::npos) << status.message();
    EXPECT_NE(status.message().find("cudaErrorMemoryAllocation"), std::string::npos) << status.message();

    auto sim = create_or_fail(forest_scene(15), test_config(BackendKind::cuda, Composition::pointer_jumping, false));
    ASSERT_TRUE(sim);
    EXPECT_TRUE(sim->step(3).ok());
}

TEST(CudaErrors, RangesPastTheEndAreRejected) {
    HMSM_SKIP_WITHOUT_CUDA();
    auto sim = create_or_fail(forest_scene(16), test_config(BackendKind::cuda, Composition::pointer_jumping, false));
    ASSERT_TRUE(sim);
    const uint64_t nodes = sim->node_count();
    std::vector<double> values(8 * 4);
    const Status status = hmsm::detail::backend_of(*sim).read(BufferId::node_world, nodes - 4, 8, values.data(), Scalar::f64);
    EXPECT_EQ(status.code(), ErrorCode::invalid_argument);
    EXPECT_NE(status.message().find("node_world"), std::string::npos);
}

TEST(CudaReadback, ChunkedPinnedReadsMatchTheCpuAndEachOther) {
    // 45 paper-5 trees: 708k vertices, 11 MB of vertex_position, more than one 8 MiB half of
    // the pinned staging buffer, so reads take two chunks whose copy and conversion overlap.
    HMSM_SKIP_WITHOUT_CUDA();
    auto paper = generate_preset("paper-5");
    ASSERT_TRUE(paper.ok());
    auto scene = grid_scene(*paper, 45, 20.0, 5);
    ASSERT_TRUE(scene.ok());
    auto device = create_or_fail(*scene, test_config(BackendKind::cuda, Composition::pointer_jumping, false));
    auto reference = create_or_fail(*scene, test_config(BackendKind::cpu, Composition::pointer_jumping, false));
    ASSERT_TRUE(device && reference);
    ASSERT_GT(device->vertex_count() * 16, 8ull << 20);
    ASSERT_TRUE(device->step(5).ok());
    ASSERT_TRUE(reference->step(5).ok());
    std::vector<float> as_float, expected;
    std::vector<double> as_double;
    ASSERT_TRUE(device->read(Output::vertex_positions, as_float).ok());
    ASSERT_TRUE(device->read(Output::vertex_positions, as_double).ok());
    ASSERT_TRUE(reference->read(Output::vertex_positions, expected).ok());
    ASSERT_EQ(as_float.size(), expected.size());
    ASSERT_EQ(as_double.size(), expected.size());
    for (size_t i = 0; i < as_float.size(); ++i) ASSERT_EQ(double(as_float[i]), as_double[i]) << i;
    const std::vector<double> expected_double(expected.begin(), expected.end());
    EXPECT_LE(max_abs_difference(as_double, expected_double) / scene_height(*scene), 1e-4);
    // A read that starts and ends inside chunks returns the same words as the whole read.
    const uint64_t first = 123457, count = device->vertex_count() - first - 1001;
    ASSERT_GT(count * 16, 8ull << 20);  // still two chunks
    std::vector<float> part(4 * count);
    ASSERT_TRUE(hmsm::detail::backend_of(*device).read(BufferId::vertex_position, first, count, part.data(), Scalar::f32).ok());
    for (uint64_t i = 0; i < count; ++i)
        for (uint64_t k = 0; k < 3; ++k) ASSERT_EQ(part[4 * i + k], as_float[3 * (first + i) + k]) << i;
}

/// In a fresh process (a sticky error ruins the CUDA context for good): a jump table pointing
/// far outside the buffers makes compose fault; the step must report device_error with the
/// CUDA error name, and later calls must fail the same way instead of aborting.
[[noreturn]] void fault_and_exit() {
    auto sim = Simulation::create(forest_scene(17), test_config(BackendKind::cuda, Composition::pointer_jumping, false));
    if (!sim.ok()) std::exit(2);
    const uint64_t count = hmsm::detail::scene_data_of(**sim).element_count(BufferId::chain_jump);
    std::vector<double> far(count, double(0x7fffff00));
    if (!hmsm::detail::backend_of(**sim).write(BufferId::chain_jump, 0, count, far.data(), Scalar::f64).ok()) std::exit(3);
    const Status step = (*sim)->step(1);
    if (step.code() != ErrorCode::device_error || step.message().find("cudaError") == std::string::npos) {
        std::fprintf(stderr, "step: %s\n", step.message().c_str());
        std::exit(4);
    }
    std::fprintf(stderr, "step failed as expected: %s\n", step.message().c_str());
    std::vector<float> positions;
    if ((*sim)->read(Output::node_positions, positions).code() != ErrorCode::device_error) std::exit(5);
    sim = Status{};  // destroying the simulation on a broken context must not abort either
    std::exit(0);
}

TEST(CudaErrorsStickyDeathTest, DeviceFaultIsAnErrorValue) {
    HMSM_SKIP_WITHOUT_CUDA();
    GTEST_FLAG_SET(death_test_style, "threadsafe");
    EXPECT_EXIT(fault_and_exit(), ::testing::ExitedWithCode(0), "step failed as expected: .*cudaError");
}

}  // namespace
}  // namespace hmsm::cuda_test
