// The Vulkan backend through Simulation and directly: profiling, chunked submission, buffer
// round trips and the 2-D dispatch grid (the storage-buffer-range split: window_test.cpp).
#include "simulation_access.h"
#include "random_scene.h"
#include "test_trees.h"
#include "vulkan_test_support.h"

#include "vulkan/fault_injection.h"
#include "vulkan/recorder.h"

#include <cstdlib>
#include <string_view>

namespace hmsm::test {
namespace {

using detail::BufferId;

SimulationConfig windy_config() {
    SimulationConfig config;
    config.wind.strength = 8.0;
    config.wind.direction = {1, 0, 0.3};
    return config;
}

TEST_F(VulkanTest, ProfilingGivesEveryPassATime) {
    std::string skip;
    SimulationConfig config = windy_config();
    config.profile_passes = true;
    config.composition = Composition::pointer_jumping;  // a dispatch per pass (the default may pair them)
    auto sim = create_simulation_or_skip(*grid_scene(small_tree(), 3, 5.0, 1), config,
                                         BackendKind::vulkan, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(sim);
    ASSERT_TRUE(sim->step(400).ok());  // several command buffers of steps
    PassTimes times = sim->pass_times();
    EXPECT_EQ(times.steps, 400u);
    for (Pass pass : kAllPasses) EXPECT_GT(times.seconds[uint32_t(pass)], 0.0) << pass_name(pass);

    hmsm::detail::backend_of(*sim).set_profiling(false);
    ASSERT_TRUE(sim->step(3).ok());
    EXPECT_EQ(sim->pass_times().total(), 0.0);
    EXPECT_EQ(sim->pass_times().steps, 0u);
}

TEST_F(VulkanTest, RoundsRunInOneDispatchForModelsOfUpTo1024Chains) {
    // Dispatches cost more on Vulkan, so pointer_jumping keeps the rounds in one dispatch for
    // models that one 1,024-wide workgroup covers; the CPU (like CUDA) takes one per round.
    const Scene scene = single_tree_scene(test::broom(700));
    SimulationConfig config = windy_config();
    config.composition = Composition::pointer_jumping;  // (the default is path walk on a GPU)
    std::string skip;
    auto vulkan = create_simulation_or_skip(scene, config, BackendKind::vulkan, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    auto cpu = create_simulation_or_skip(scene, config, BackendKind::cpu, skip);
    ASSERT_TRUE(vulkan && cpu);
    for (const auto& [sim, kind] : {std::pair{vulkan.get(), HMSM_DISPATCH_JUMP_ROUNDS_IN_DISPATCH},
                                    std::pair{cpu.get(), HMSM_DISPATCH_JUMP_ROUND}})
        for (const auto& d : hmsm::detail::step_program_of(*sim))
            if (d.pass == Pass::compose || d.pass == Pass::root_positions) EXPECT_EQ(d.constants.kind, kind);
    ASSERT_TRUE(vulkan->step(20).ok());
    ASSERT_TRUE(cpu->step(20).ok());
    std::vector<double> a, b;
    ASSERT_TRUE(vulkan->read(Output::node_positions, a).ok());
    ASSERT_TRUE(cpu->read(Output::node_positions, b).ok());
    EXPECT_LE(test::max_abs_difference(a, b), 1e-4 * 10.0);
}

TEST_F(VulkanTest, CopyBandwidthIsMeasuredOnTheDevice) {
    std::string skip;
    auto sim = create_simulation_or_skip(single_tree_scene(small_tree()), windy_config(),
                                         BackendKind::vulkan, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(sim);
    auto bandwidth = hmsm::detail::backend_of(*sim).measure_copy_bandwidth(8u << 20);
    ASSERT_TRUE(bandwidth.ok()) << bandwidth.status().message();
    EXPECT_GT(*bandwidth, 1e8);    // more than 0.1 GB/s on any device, lavapipe included
    EXPECT_LT(*bandwidth, 1e14);   // and less than 100 TB/s
}

/// Turns an injected fault on for one test and off again, whatever the test does.
struct InjectedFault {
    InjectedFault(detail::VulkanFault fault, uint32_t after) { detail::vulkan_inject_fault(fault, after); }
    ~InjectedFault() { detail::vulkan_inject_fault(detail::VulkanFault::none); }
};

TEST_F(VulkanTest, OutOfDeviceMemoryAtUploadIsAnError) {
    std::string skip;
    auto probe = create_simulation_or_skip(single_tree_scene(small_tree()), windy_config(),
                                           BackendKind::vulkan, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    InjectedFault fault(detail::VulkanFault::out_of_device_memory_at_upload, 0);
    SimulationConfig config = windy_config();
    config.backend = BackendKind::vulkan;
    auto sim = Simulation::create(single_tree_scene(small_tree()), config);
    ASSERT_FALSE(sim.ok());
    EXPECT_EQ(sim.status().code(), ErrorCode::out_of_memory);
    EXPECT_NE(sim.status().message().find("VK_ERROR_OUT_OF_DEVICE_MEMORY"), std::string::npos)
        << sim.status().message();
}

TEST_F(VulkanTest, DeviceLostMidRunFailsThatStepAndEveryLaterCall) {
    std::string skip;
    std::unique_ptr<Simulation> sim;
    {
        // One submission succeeds (the rest pose at creation); the first step's is lost.
        InjectedFault fault(detail::VulkanFault::device_lost_at_submit, 1);
        sim = create_simulation_or_skip(single_tree_scene(small_tree()), windy_config(),
                                        BackendKind::vulkan, skip);
    }
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(sim);
    Status stepped = sim->step(5);
    EXPECT_EQ(stepped.code(), ErrorCode::device_error);
    EXPECT_NE(stepped.message().find("VK_ERROR_DEVICE_LOST"), std::string::npos) << stepped.message();
    EXPECT_EQ(sim->steps_done(), 0u);  // a failed step does not advance the clock
    EXPECT_EQ(sim->step(1).code(), ErrorCode::device_error);  // lost for good
    std::vector<float> positions;
    EXPECT_EQ(sim->read(Output::node_positions, positions).code(), ErrorCode::device_error);
    sim.reset();  // and it still tears down without hanging
}

TEST_F(VulkanTest, StepsGiveTheSameResultInOneCallOrMany) {
    // One call records several command buffers (two in flight); one step per call records one.
    std::string skip;
    Scene scene = *grid_scene(deep_tree(5), 4, 6.0, 9);
    auto batched = create_simulation_or_skip(scene, windy_config(), BackendKind::vulkan, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    auto single = create_simulation_or_skip(scene, windy_config(), BackendKind::vulkan, skip);
    ASSERT_TRUE(batched && single);
    ASSERT_TRUE(batched->step(600).ok());
    for (int k = 0; k < 600; ++k) ASSERT_TRUE(single->step(1).ok());
    std::vector<float> a, b;
    ASSERT_TRUE(batched->read(Output::vertex_positions, a).ok());
    ASSERT_TRUE(single->read(Output::vertex_positions, b).ok());
    EXPECT_EQ(a, b);  // same device, same dispatches: bitwise identical
}

TEST_F(VulkanTest, EveryBufferRoundTripsThroughWriteAndRead) {
    std::mt19937 rng(5);
    detail::SceneData data = random_scene_data(rng, {{7, 13, 101}}, {0, 0, 0}, 2);
    // The coupled dynamics' buffers have elements only in a coupled scene.
    data.dynamics = Dynamics::coupled;
    data.chain_dynamics.assign(size_t(4 * HMSM_CHAIN_DYNAMICS_VEC4S) * data.total_model_chains(), 0.5);
    std::string skip;
    auto vulkan = create_vulkan_or_skip(skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(vulkan);
    ASSERT_TRUE(vulkan->upload(data).ok());
    for (const auto& info : detail::kBufferTable) {
        SCOPED_TRACE(std::string(info.name));
        const uint64_t count = data.element_count(info.id);
        const uint32_t scalars = detail::shape_scalars(info.shape);
        std::vector<float> values(count * scalars);
        for (size_t i = 0; i < values.size(); ++i)
            values[i] = detail::shape_is_integer(info.shape) ? float(int(i % 1000) - 500) : float(i) * 0.25f - 3.0f;
        // A sub-range first, then the whole buffer; read back as float and as double.
        ASSERT_TRUE(vulkan->write(info.id, 1, count - 1, values.data() + scalars, detail::Scalar::f32).ok());
        ASSERT_TRUE(vulkan->write(info.id, 0, 1, values.data(), detail::Scalar::f32).ok());
        std::vector<float> as_float(values.size());
        ASSERT_TRUE(vulkan->read(info.id, 0, count, as_float.data(), detail::Scalar::f32).ok());
        EXPECT_EQ(as_float, values);
        std::vector<double> as_double = read_buffer(*vulkan, info.id, count);
        EXPECT_EQ(as_double, std::vector<double>(values.begin(), values.end()));
    }
    double dummy[12];
    Status past = vulkan->read(BufferId::chain_state, data.total_chains, 1, dummy, detail::Scalar::f64);
    EXPECT_EQ(past.code(), ErrorCode::invalid_argument);
    EXPECT_NE(past.message().find("chain_state"), std::string::npos) << past.message();
}

TEST_F(VulkanTest, StaticBuffersHoldTheSceneInFloat) {
    std::mt19937 rng(8);
    detail::SceneData data = random_scene_data(rng, {{11, 20, 70}, {3, 5, 9}}, {1, 0, 1}, 4);
    std::string skip;
    auto vulkan = create_vulkan_or_skip(skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    auto oracle = detail::create_cpu_backend(true);
    ASSERT_TRUE(vulkan && oracle.ok());
    ASSERT_TRUE(vulkan->upload(data).ok());
    ASSERT_TRUE(oracle.value()->upload(data).ok());
    for (const auto& info : detail::kBufferTable) {
        const uint64_t count = data.element_count(info.id);
        EXPECT_LE(relative_difference(read_buffer(*vulkan, info.id, count),
                                      read_buffer(*oracle.value(), info.id, count)),
                  1e-7)
            << info.name;
    }
}

TEST_F(VulkanTest, WorkgroupGridGoesTwoDimensionalPastTheLimit) {
    detail::vk::DeviceLimits limits;
    limits.max_workgroup_count[0] = limits.max_workgroup_count[1] = 65535;
    auto grid = detail::vk::workgroup_grid(65535u, limits);
    EXPECT_EQ(grid.x, 65535u);
    EXPECT_EQ(grid.y, 1u);
    grid = detail::vk::workgroup_grid(65536u, limits);
    EXPECT_EQ(grid.x, 65535u);
    EXPECT_EQ(grid.y, 2u);
    const uint64_t most = (uint64_t(UINT32_MAX) + HMSM_WORKGROUP_SIZE - 1) / HMSM_WORKGROUP_SIZE;
    grid = detail::vk::workgroup_grid(most, limits);
    EXPECT_GE(uint64_t(grid.x) * grid.y, most);
    EXPECT_LE(grid.y, 65535u);
    EXPECT_EQ(detail::vk::workgroup_grid(0, limits).x, 0u);
    EXPECT_EQ(detail::vk::workgroup_grid(1, limits).x, 1u);
}

TEST_F(VulkanTest, DispatchBeyondTheWorkgroupCountLimitMatchesCpu64) {
    // A contour dispatch of more than 65535 * 64 threads (the usual maxComputeWorkGroupCount[0])
    // runs on a 2-D grid; its last vertices must still be right.
    std::mt19937 rng(21);
    const uint32_t vertices = 65535u * HMSM_WORKGROUP_SIZE / 4 + 4099;
    detail::SceneData data = random_scene_data(rng, {{9, 17, vertices}}, {0, 0, 0, 0}, 4);
    std::string skip;
    auto vulkan = create_vulkan_or_skip(skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    auto oracle = detail::create_cpu_backend(true);
    ASSERT_TRUE(vulkan && oracle.ok());
    ASSERT_TRUE(vulkan->upload(data).ok());
    ASSERT_TRUE(oracle.value()->upload(data).ok());
    randomize_state(data, *vulkan, *oracle.value(), rng);
    auto variants = pass_variants(data, Pass::contour, PassForm::jump_per_round, rng);
    ASSERT_EQ(variants.size(), 1u);
    ASSERT_GT(variants[0][0].constants.element_count, 65535u * HMSM_WORKGROUP_SIZE);
    const detail::RunStep step[1] = {};
    ASSERT_TRUE(vulkan->run(variants[0], step).ok());
    ASSERT_TRUE(oracle.value()->run(variants[0], step).ok());
    const uint64_t tail = 300000, first = data.total_vertices - tail;
    std::vector<double> a(tail * 4), b(tail * 4);
    ASSERT_TRUE(vulkan->read(BufferId::vertex_position, first, tail, a.data(), detail::Scalar::f64).ok());
    ASSERT_TRUE(oracle.value()->read(BufferId::vertex_position, first, tail, b.data(), detail::Scalar::f64).ok());
    EXPECT_LE(relative_difference(a, b), 2e-5);
}

}  // namespace
}  // namespace hmsm::test

namespace hmsm::test {
namespace {

// Reads and writes of scattered ranges take one submission each, whatever their number (that
// they agree with one-range calls: range_transfers_test.cpp).
TEST_F(VulkanTest, ScatteredRangesTakeOneSubmission) {
    if (!detail::batch_transfers_enabled()) GTEST_SKIP() << "HMSM_BATCH_TRANSFERS=0";
    std::string skip;
    auto sim = create_simulation_or_skip(*grid_scene(small_tree(), 40, 5.0, 1), windy_config(), BackendKind::vulkan, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(sim);
    ASSERT_TRUE(sim->step(3).ok());
    const auto& backend = dynamic_cast<const detail::vk::VulkanBackend&>(hmsm::detail::backend_of(*sim));
    auto& mutable_backend = hmsm::detail::backend_of(*sim);
    const uint64_t chains = hmsm::detail::scene_data_of(*sim).element_count(BufferId::chain_state);
    ASSERT_GT(chains, 200u);
    std::vector<detail::ElementRange> ranges;
    uint64_t total = 0;
    for (uint64_t first = 1; first + 3 < chains; first += 7) {
        ranges.push_back({first, 3});
        total += 3;
    }
    ASSERT_GT(ranges.size(), 20u);
    std::vector<float> values(total * 4);
    uint64_t before = backend.submissions();
    ASSERT_TRUE(mutable_backend.read_ranges(BufferId::chain_state, ranges, values.data(), detail::Scalar::f32).ok());
    EXPECT_EQ(backend.submissions() - before, 1u);
    before = backend.submissions();
    ASSERT_TRUE(mutable_backend.write_ranges(BufferId::chain_state, ranges, values.data(), detail::Scalar::f32).ok());
    EXPECT_EQ(backend.submissions() - before, 1u);
    // Two buffers at once: still one submission each way.
    std::vector<float> forces(total * 2);
    const detail::BufferRangesRead reads[] = {{BufferId::chain_state, ranges, values.data()},
                                              {BufferId::chain_force, ranges, forces.data()}};
    before = backend.submissions();
    ASSERT_TRUE(mutable_backend.read_buffers(reads, detail::Scalar::f32).ok());
    EXPECT_EQ(backend.submissions() - before, 1u);
    const detail::BufferRangesWrite writes[] = {{BufferId::chain_state, ranges, values.data()},
                                                {BufferId::chain_force, ranges, forces.data()}};
    before = backend.submissions();
    ASSERT_TRUE(mutable_backend.write_buffers(writes, detail::Scalar::f32).ok());
    EXPECT_EQ(backend.submissions() - before, 1u);
}

// Moves go through the range copy (shaders/glsl/copy_ranges.comp), a gather and a scatter per
// buffer and batch, and land as applied one after another, overlapping each other and
// themselves.
TEST_F(VulkanTest, MovesGoThroughTheRangeCopy) {
    if (!detail::batch_transfers_enabled()) GTEST_SKIP() << "HMSM_BATCH_TRANSFERS=0";
    const char* off = std::getenv("HMSM_VULKAN_RANGE_COPIES");
    if (off && std::string_view(off) == "0") GTEST_SKIP() << "HMSM_VULKAN_RANGE_COPIES=0";
    std::string skip;
    const char* shader_ranges_were = std::getenv("HMSM_VULKAN_SHADER_RANGES");
    const std::string shader_ranges_before = shader_ranges_were ? shader_ranges_were : "";
    ::setenv("HMSM_VULKAN_SHADER_RANGES", "1", 1);  // the default, whatever the environment says
    auto sim = create_simulation_or_skip(*grid_scene(small_tree(), 40, 5.0, 1), windy_config(), BackendKind::vulkan, skip);
    if (shader_ranges_were) ::setenv("HMSM_VULKAN_SHADER_RANGES", shader_ranges_before.c_str(), 1);
    else ::unsetenv("HMSM_VULKAN_SHADER_RANGES");
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(sim);
    ASSERT_TRUE(sim->step(3).ok());
    const auto& backend = dynamic_cast<const detail::vk::VulkanBackend&>(hmsm::detail::backend_of(*sim));
    auto& mutable_backend = hmsm::detail::backend_of(*sim);
    const uint64_t chains = hmsm::detail::scene_data_of(*sim).element_count(BufferId::chain_force);
    ASSERT_GT(chains, 260u);
    // Moves that overlap each other and themselves, against the same moves applied in order.
    std::vector<float> whole(chains * 2), expected;
    ASSERT_TRUE(mutable_backend.read(BufferId::chain_force, 0, chains, whole.data(), detail::Scalar::f32).ok());
    expected = whole;
    const detail::ElementMove moves[] = {{10, 13, 40}, {100, 60, 50}, {5, 200, 7}};
    for (const detail::ElementMove& m : moves) {
        const std::vector<float> source(expected.begin() + 2 * m.src, expected.begin() + 2 * (m.src + m.count));
        std::copy(source.begin(), source.end(), expected.begin() + 2 * m.dst);
    }
    const uint64_t before = backend.range_copy_dispatches();
    ASSERT_TRUE(mutable_backend.move_elements(BufferId::chain_force, moves).ok());
    EXPECT_GE(backend.range_copy_dispatches() - before, 2u);
    ASSERT_TRUE(mutable_backend.read(BufferId::chain_force, 0, chains, whole.data(), detail::Scalar::f32).ok());
    EXPECT_EQ(whole, expected);

    // Pattern copies: one dispatch of copy_patterns.comp per buffer, the copies as expanded.
    ASSERT_TRUE(backend.capabilities().copies_patterns);
    const detail::ElementMove pattern[] = {{0, 1, 3}, {7, 5, 2}};
    const detail::MovePattern patterns[] = {{pattern}};
    const detail::PatternCopy copies[] = {{20, 150, 0}, {40, 170, 0}, {3, 230, 0}};
    for (const detail::PatternCopy& c : copies)
        for (const detail::ElementMove& m : pattern)
            std::copy_n(expected.begin() + 2 * (c.src + m.src), 2 * m.count, expected.begin() + 2 * (c.dst + m.dst));
    const uint64_t before_patterns = backend.range_copy_dispatches();
    const BufferId ids[] = {BufferId::chain_force};
    ASSERT_TRUE(mutable_backend.copy_patterns(ids, 0, patterns, copies).ok());
    EXPECT_EQ(backend.range_copy_dispatches() - before_patterns, 1u);
    ASSERT_TRUE(mutable_backend.read(BufferId::chain_force, 0, chains, whole.data(), detail::Scalar::f32).ok());
    EXPECT_EQ(whole, expected);

    // A write of many ranges: one scatter of the range copy instead of a copy region each, in
    // the submission that copies the values into the scratch (one submission waited for).
    std::vector<detail::ElementRange> ranges;
    std::vector<float> values;
    for (uint64_t e = 1; e + 1 < chains && ranges.size() < 100; e += 2) {
        ranges.push_back({e, 1});
        values.insert(values.end(), {float(e), -float(e)});
        expected[2 * e] = float(e);
        expected[2 * e + 1] = -float(e);
    }
    ASSERT_GE(ranges.size(), 64u);
    const uint64_t before_writes = backend.range_copy_dispatches(), submitted = backend.submissions();
    ASSERT_TRUE(mutable_backend.write_ranges(BufferId::chain_force, ranges, values.data(), detail::Scalar::f32).ok());
    EXPECT_EQ(backend.range_copy_dispatches() - before_writes, 1u);
    EXPECT_EQ(backend.submissions() - submitted, 1u);
    ASSERT_TRUE(mutable_backend.read(BufferId::chain_force, 0, chains, whole.data(), detail::Scalar::f32).ok());
    EXPECT_EQ(whole, expected);

    // A read of many ranges: one gather of the range copy, the ranges back to back.
    std::vector<float> read_back(values.size(), -1.0f);
    const uint64_t before_reads = backend.range_copy_dispatches();
    ASSERT_TRUE(backend.read_ranges(BufferId::chain_force, ranges, read_back.data(), detail::Scalar::f32).ok());
    EXPECT_EQ(backend.range_copy_dispatches() - before_reads, 1u);
    EXPECT_EQ(read_back, values);
}

}  // namespace
}  // namespace hmsm::test
