// Scenes whose state buffers exceed one descriptor's window (src/vulkan/windows.h): forced small
// windows on small scenes must give bitwise the results of the unsplit run (the same shader
// arithmetic) and agree with cpu64; one instance larger than a window is refused; read/write
// cross segment boundaries; and a scene beyond lavapipe's real maxStorageBufferRange runs.
#include "simulation_access.h"
#include "random_scene.h"
#include "test_compositions.h"
#include "test_trees.h"
#include "engine_device.h"
#include "vulkan_test_support.h"

#include "vulkan/windows.h"

#include <hmsm/vulkan.h>

#include <cmath>
#include <random>
#include <tuple>

namespace hmsm::test {
namespace {

using detail::BufferId;

/// Forces windows of `bytes` (starts aligned to `alignment` too) for the backends created
/// while it lives.
struct ForcedWindow {
    explicit ForcedWindow(uint64_t bytes, uint64_t alignment = 0) {
        detail::vulkan_set_window_bytes(bytes, alignment);
    }
    ~ForcedWindow() { detail::vulkan_set_window_bytes(0); }
};

const detail::vk::VulkanBackend& vulkan_of(const Simulation& sim) {
    return dynamic_cast<const detail::vk::VulkanBackend&>(hmsm::detail::backend_of(sim));
}

SimulationConfig windy_config(Composition composition) {
    SimulationConfig config;
    config.wind.strength = 8.0;
    config.wind.direction = {1, 0, 0.3};
    config.wind.front_speed = 4.0;
    config.wind.profile = WindProfile::y1;
    config.composition = composition;
    return config;
}

/// Two models in several runs (instance groups), odd counts.
Scene two_model_scene() {
    Scene scene;
    scene.models = {small_tree(), deep_tree(6)};
    scene.model_names = {"small", "deep"};
    const uint32_t models[] = {0, 0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 0, 0, 0, 0, 1, 0};
    for (uint32_t i = 0; i < std::size(models); ++i)
        scene.instances.push_back({models[i], {3.0 * (i % 5), 0.0, 4.0 * (i / 5)}, 0.37 * i});
    return scene;
}

/// The largest window one instance of `data` needs, alignment slack included.
uint64_t instance_bytes(const detail::SceneData& data, uint64_t alignment) {
    uint64_t bytes = 0;
    const uint64_t slack = alignment / 8 + 1;  // elements a window start may move back
    for (const detail::ModelRange& m : data.models) {
        bytes = std::max<uint64_t>(bytes, (m.vertex_count + slack) * 16);
        bytes = std::max<uint64_t>(bytes, (m.node_count + slack) * 16);
        bytes = std::max<uint64_t>(bytes, 2 * (m.chain_count + 2 * slack) * 48);
    }
    return bytes + 2 * alignment;
}

std::vector<float> read_f32(const Simulation& sim, Output output) {
    std::vector<float> values;
    Status s = sim.read(output, values);
    EXPECT_TRUE(s.ok()) << s.message();
    return values;
}
std::vector<double> read_f64(const Simulation& sim, Output output) {
    std::vector<double> values;
    Status s = sim.read(output, values);
    EXPECT_TRUE(s.ok()) << s.message();
    return values;
}

TEST_F(VulkanTest, SplitScenesMatchTheUnsplitRunBitwise) {
    const Scene scenes[] = {two_model_scene(), *grid_scene(small_tree(), 11, 5.0, 3)};
    for (TestComposition composition : {kJumpingPerRound, kJumpingInDispatch, TestComposition(Composition::level_by_level),
                                        TestComposition(Composition::path_walk)}) {
        for (const Scene& scene : scenes) {
            SCOPED_TRACE(name_of(composition) + " models " + std::to_string(scene.models.size()));
            const SimulationConfig config = windy_config(composition.composition);
            std::string skip;
            auto whole = create_simulation_or_skip(scene, config, BackendKind::vulkan, skip, composition.jumping_form);
            if (!skip.empty()) GTEST_SKIP() << skip;
            ASSERT_TRUE(whole);
            ASSERT_EQ(vulkan_of(*whole).window_plan().segments().size(), 1u);
            ASSERT_TRUE(whole->step(60).ok());
            auto oracle = create_simulation_or_skip(scene, config, BackendKind::cpu64, skip);
            ASSERT_TRUE(oracle && oracle->step(60).ok());

            // About one, two and three instances per window, at odd sizes; window starts
            // aligned as the device asks, and to 256 bytes (a GPU's alignment: more slack).
            const uint64_t device_alignment =
                vulkan_of(*whole).device().limits().min_storage_buffer_offset_alignment;
            for (auto [instances, extra, alignment] :
                 {std::tuple{1, 4, uint64_t(0)}, std::tuple{2, 13, uint64_t(0)}, std::tuple{3, 101, uint64_t(0)},
                  std::tuple{1, 4, uint64_t(256)}, std::tuple{2, 29, uint64_t(256)}}) {
                const uint64_t one = instance_bytes(hmsm::detail::scene_data_of(*whole), std::max(alignment, device_alignment));
                const uint64_t window = instances * one + extra;
                SCOPED_TRACE("window " + std::to_string(window) + " alignment " + std::to_string(alignment));
                std::unique_ptr<Simulation> split;
                {
                    ForcedWindow forced(window, alignment);
                    split = create_simulation_or_skip(scene, config, BackendKind::vulkan, skip, composition.jumping_form);
                }
                ASSERT_TRUE(split);
                const auto& segments = vulkan_of(*split).window_plan().segments();
                EXPECT_GT(segments.size(), 2u);
                ASSERT_TRUE(split->step(25).ok());
                ASSERT_TRUE(split->step(35).ok());
                for (Output o : kEveryOutput) EXPECT_EQ(read_f32(*split, o), read_f32(*whole, o)) << int(o);
                double height = 0.0;
                for (const TreeModel& m : scene.models) height = std::max(height, tree_height(m));
                for (Output o : {Output::node_positions, Output::vertex_positions})
                    EXPECT_LE(max_abs_difference(read_f64(*split, o), read_f64(*oracle, o)) / height, 1e-4);
            }
        }
    }
}

TEST_F(VulkanTest, SplitScenesFollowLiveChangesBitwise) {
    // Live changes on a scene cut into windows: instance_wind windows, active runs split across
    // segments, and instances removed and added (a new window plan) give the unsplit result.
    const Scene scene = *grid_scene(small_tree(), 9, 5.0, 3);
    const SimulationConfig config = windy_config(Composition::pointer_jumping);
    std::string skip;
    auto whole = create_simulation_or_skip(scene, config, BackendKind::vulkan, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(whole);
    const uint64_t one = instance_bytes(hmsm::detail::scene_data_of(*whole),
                                        vulkan_of(*whole).device().limits().min_storage_buffer_offset_alignment);
    std::unique_ptr<Simulation> split;
    {
        ForcedWindow forced(2 * one + 13);
        split = create_simulation_or_skip(scene, config, BackendKind::vulkan, skip);
    }
    ASSERT_TRUE(split);
    ASSERT_GT(vulkan_of(*split).window_plan().segments().size(), 2u);
    auto change = [](Simulation& sim) {
        Wind wind = sim.wind();
        wind.profile = WindProfile::turbulent;
        wind.front_speed = 2.0;
        ASSERT_TRUE(sim.set_wind(wind).ok());
        ASSERT_TRUE(sim.set_instance_wind_scale(4, 1.7).ok());
        ASSERT_TRUE(sim.set_instance_active(2, false).ok());
        ASSERT_TRUE(sim.set_instance_active(5, false).ok());
        const uint64_t gone[] = {0, 6};
        ASSERT_TRUE(sim.remove_instances(gone).ok());
        const Instance added[] = {{0, {20, 0, 20}, 0.3}, {0, {-20, 0, 20}, 1.3, 0.5, 0.5}};
        ASSERT_TRUE(sim.add_instances(added).ok());
    };
    ASSERT_TRUE(whole->step(20).ok());
    ASSERT_TRUE(split->step(20).ok());
    for (Output o : kEveryOutput) EXPECT_EQ(read_f32(*split, o), read_f32(*whole, o)) << "before " << int(o);
    change(*whole);
    change(*split);
    ASSERT_TRUE(whole->step(30).ok());
    ASSERT_TRUE(split->step(30).ok());
    EXPECT_GT(vulkan_of(*split).window_plan().segments().size(), 2u);
    for (Output o : kEveryOutput) EXPECT_EQ(read_f32(*split, o), read_f32(*whole, o)) << int(o);
}

TEST_F(VulkanTest, SegmentsCutInstanceGroupsIntoSeveralParts) {
    std::string skip;
    Scene scene = two_model_scene();
    auto whole = create_simulation_or_skip(scene, windy_config(Composition::pointer_jumping),
                                           BackendKind::vulkan, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(whole);
    const uint64_t alignment = vulkan_of(*whole).device().limits().min_storage_buffer_offset_alignment;
    ForcedWindow forced(2 * instance_bytes(hmsm::detail::scene_data_of(*whole), alignment) + 13);
    auto split = create_simulation_or_skip(scene, windy_config(Composition::pointer_jumping),
                                           BackendKind::vulkan, skip);
    ASSERT_TRUE(split);
    const auto& plan = vulkan_of(*split).window_plan();
    // Some group spans several segments, and every dispatch's parts cover its threads exactly.
    bool cut = false;
    for (const detail::Dispatch& d : hmsm::detail::step_program_of(*split)) {
        uint64_t threads = 0;
        uint32_t parts = 0;
        plan.for_each_part(d, [&](uint32_t segment, const gpu::PassConstants& c) {
            ++parts;
            threads += c.element_count;
            const auto& s = plan.segments()[segment];
            EXPECT_EQ(c.total_chains, s.halves_stride);
            EXPECT_LE(plan.window(BufferId::vertex_position, segment).bytes, plan.window_bytes());
            EXPECT_LE(plan.window(BufferId::chain_rotation, segment).bytes, plan.window_bytes());
        });
        EXPECT_EQ(threads, d.constants.element_count);
        cut = cut || parts > 1;
    }
    EXPECT_TRUE(cut);
    // As recorded: every dispatch ends in exactly one last part (its timestamp).
    const auto expanded = plan.expand(hmsm::detail::step_program_of(*split));
    EXPECT_GT(expanded.size(), hmsm::detail::step_program_of(*split).size());
    size_t last = 0;
    for (const auto& part : expanded) last += part.last;
    EXPECT_EQ(last, hmsm::detail::step_program_of(*split).size());

    // Profiling a split scene: one time per dispatch, every pass timed.
    hmsm::detail::backend_of(*split).set_profiling(true);
    ASSERT_TRUE(split->step(3).ok());
    const PassTimes times = split->pass_times();
    EXPECT_EQ(times.steps, 3u);
    for (Pass pass : kAllPasses) EXPECT_GT(times.seconds[uint32_t(pass)], 0.0) << pass_name(pass);
}

TEST_F(VulkanTest, InstanceLargerThanAWindowIsRefused) {
    std::string skip;
    auto probe = create_simulation_or_skip(single_tree_scene(small_tree()), windy_config(Composition::pointer_jumping),
                                           BackendKind::vulkan, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ForcedWindow forced(256);
    SimulationConfig config = windy_config(Composition::pointer_jumping);
    config.backend = BackendKind::vulkan;
    auto sim = Simulation::create(*grid_scene(small_tree(), 3, 5.0, 1), config);
    ASSERT_FALSE(sim.ok());
    EXPECT_EQ(sim.status().code(), ErrorCode::unsupported);
    EXPECT_NE(sim.status().message().find("instance 0 alone needs"), std::string::npos) << sim.status().message();
    EXPECT_NE(sim.status().message().find("maxStorageBufferRange"), std::string::npos) << sim.status().message();
}

TEST_F(VulkanTest, ReadAndWriteCrossSegments) {
    std::string skip;
    Scene scene = two_model_scene();
    auto probe = create_simulation_or_skip(scene, windy_config(Composition::pointer_jumping),
                                           BackendKind::vulkan, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    const uint64_t alignment = vulkan_of(*probe).device().limits().min_storage_buffer_offset_alignment;
    ForcedWindow forced(instance_bytes(hmsm::detail::scene_data_of(*probe), alignment) + 4);
    auto sim = create_simulation_or_skip(scene, windy_config(Composition::pointer_jumping),
                                         BackendKind::vulkan, skip);
    ASSERT_TRUE(sim);
    ASSERT_GT(vulkan_of(*sim).window_plan().segments().size(), 2u);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    const auto& data = hmsm::detail::scene_data_of(*sim);
    for (BufferId id : {BufferId::chain_rotation, BufferId::chain_origin, BufferId::chain_state,
                        BufferId::vertex_position}) {
        SCOPED_TRACE(std::string(detail::buffer_info(id).name));
        const uint64_t count = data.element_count(id);
        const uint32_t scalars = detail::shape_scalars(detail::buffer_info(id).shape);
        std::vector<float> values(count * scalars);
        for (float& v : values) v = float(unit(rng));
        ASSERT_TRUE(hmsm::detail::backend_of(*sim).write(id, 0, count, values.data(), detail::Scalar::f32).ok());
        std::vector<float> back(count * scalars);
        ASSERT_TRUE(hmsm::detail::backend_of(*sim).read(id, 0, count, back.data(), detail::Scalar::f32).ok());
        EXPECT_EQ(back, values);
        // A sub-range across the middle (the half boundary of the ping-pong buffers).
        const uint64_t first = count / 2 - 7, n = 19;
        std::vector<float> part(n * scalars);
        for (float& v : part) v = float(unit(rng));
        ASSERT_TRUE(hmsm::detail::backend_of(*sim).write(id, first, n, part.data(), detail::Scalar::f32).ok());
        std::copy(part.begin(), part.end(), values.begin() + first * scalars);
        ASSERT_TRUE(hmsm::detail::backend_of(*sim).read(id, 0, count, back.data(), detail::Scalar::f32).ok());
        EXPECT_EQ(back, values);
        std::vector<float> middle(n * scalars);
        ASSERT_TRUE(hmsm::detail::backend_of(*sim).read(id, first, n, middle.data(), detail::Scalar::f32).ok());
        EXPECT_EQ(middle, part);
    }
}

// A capacity beyond one window whose live instances fit in one: the scene is still bound in
// windows (its ping-pong halves as long as its live chains, not the capacity), steps as the
// unsplit run, and a range past the live chains of a half is refused instead of copied past
// the buffer (which corrupted lavapipe's heap once a growth left such a plan).
TEST_F(VulkanTest, CapacityBeyondAWindowWithOneSegmentStaysBound) {
    const Scene scene = two_model_scene();
    const SimulationConfig config = windy_config(Composition::pointer_jumping);
    std::string skip;
    auto whole = create_simulation_or_skip(scene, config, BackendKind::vulkan, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(whole && whole->step(20).ok());
    const detail::SceneData& live = hmsm::detail::scene_data_of(*whole);
    const uint64_t alignment = vulkan_of(*whole).device().limits().min_storage_buffer_offset_alignment;
    const uint64_t window = 2 * live.instance_count() * instance_bytes(live, alignment);
    std::unique_ptr<Simulation> reserved;
    {
        ForcedWindow forced(window, alignment);
        reserved = create_simulation_or_skip(scene, config, BackendKind::vulkan, skip);
    }
    ASSERT_TRUE(reserved);
    ASSERT_TRUE(reserved->reserve_instances(40 * scene.instances.size()).ok());  // re-uploaded, room past a window
    const auto& plan = vulkan_of(*reserved).window_plan();
    EXPECT_EQ(plan.segments().size(), 1u);
    EXPECT_TRUE(plan.split());
    ASSERT_TRUE(reserved->step(20).ok());
    for (Output o : kEveryOutput) EXPECT_EQ(read_f32(*reserved, o), read_f32(*whole, o)) << int(o);
    const detail::SceneData& data = hmsm::detail::scene_data_of(*reserved);
    std::vector<float> values(12 * 4, 0.0f);
    const Status past = hmsm::detail::backend_of(*reserved).write(BufferId::chain_rotation,
                                                                  data.chain_capacity + data.total_chains, 4,
                                                                  values.data(), detail::Scalar::f32);
    EXPECT_EQ(past.code(), ErrorCode::invalid_argument) << past.message();
}

TEST_F(VulkanTest, SceneBeyondTheStorageBufferRangeRuns) {
    std::string skip;
    SimulationConfig config = windy_config(Composition::pointer_jumping);
    config.model.ring_sides = 24;
    const TreeModel tree = small_tree();
    auto probe = create_simulation_or_skip(single_tree_scene(tree), config, BackendKind::vulkan, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(probe);
    const uint64_t range = vulkan_of(*probe).device().limits().max_storage_buffer_range;
    const uint64_t per_instance = probe->vertex_count();
    // Just past the range in vertex_position (16 bytes a vertex); skip on a device whose range
    // would make that scene too slow for a test.
    const uint64_t instances = range / 16 / per_instance + 1;
    if (instances * per_instance > (uint64_t(40) << 20))
        GTEST_SKIP() << "maxStorageBufferRange " << range << " needs " << instances * per_instance << " vertices";
    const uint32_t side = uint32_t(std::ceil(std::sqrt(double(instances))));
    auto grid = grid_scene(tree, side * side, 6.0, 9);
    ASSERT_TRUE(grid.ok());
    auto sim = create_simulation_or_skip(*grid, config, BackendKind::vulkan, skip);
    ASSERT_TRUE(sim);
    ASSERT_GT(sim->vertex_count() * 16, range);
    ASSERT_GT(vulkan_of(*sim).window_plan().segments().size(), 1u);
    ASSERT_TRUE(sim->step(1).ok());
    std::vector<float> positions = read_f32(*sim, Output::vertex_positions);
    // A few instances, from the first and last segments, against cpu64 alone.
    for (uint32_t i : {0u, uint32_t(grid->instances.size() / 2), uint32_t(grid->instances.size() - 1)}) {
        SCOPED_TRACE("instance " + std::to_string(i));
        Scene one;
        one.models = grid->models;
        one.model_names = grid->model_names;
        one.instances = {grid->instances[i]};
        auto oracle = create_simulation_or_skip(one, config, BackendKind::cpu64, skip);
        ASSERT_TRUE(oracle && oracle->step(1).ok());
        std::vector<double> expected = read_f64(*oracle, Output::vertex_positions);
        ASSERT_EQ(expected.size(), 3 * per_instance);
        double worst = 0.0;
        for (uint64_t k = 0; k < expected.size(); ++k)
            worst = std::max(worst, std::abs(double(positions[3 * per_instance * i + k]) - expected[k]));
        EXPECT_LE(worst / tree_height(tree), 1e-4);
    }
}

/// Outputs on demand in a split scene: joints only (no node or vertex buffers, no passes 6 and
/// 7) gives the joint matrices of the unsplit scene producing everything, bit for bit.
TEST_F(VulkanTest, SplitJointsOnlySceneMatchesTheUnsplitJoints) {
    const Scene scene = two_model_scene();
    SimulationConfig config = windy_config(Composition::pointer_jumping);
    std::string skip;
    auto whole = create_simulation_or_skip(scene, config, BackendKind::vulkan, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(whole && whole->step(40).ok());
    // Without vertex buffers an instance needs only its chain and node windows.
    const uint64_t alignment = vulkan_of(*whole).device().limits().min_storage_buffer_offset_alignment;
    const uint64_t slack = alignment / 8 + 1;
    uint64_t one = 0;
    for (const detail::ModelRange& m : hmsm::detail::scene_data_of(*whole).models)
        one = std::max<uint64_t>({one, (m.node_count + slack) * 16, 2 * (m.chain_count + 2 * slack) * 48});
    one += 2 * alignment;
    config.outputs = Outputs::joints;
    std::unique_ptr<Simulation> split;
    {
        ForcedWindow forced(2 * one + 13);
        split = create_simulation_or_skip(scene, config, BackendKind::vulkan, skip);
    }
    ASSERT_TRUE(split);
    EXPECT_GT(vulkan_of(*split).window_plan().segments().size(), 1u);
    ASSERT_TRUE(split->step(40).ok());
    EXPECT_EQ(read_f32(*split, Output::joint_matrices), read_f32(*whole, Output::joint_matrices));
    auto buffers = vulkan::shared_buffers(*split);
    ASSERT_TRUE(buffers.ok());
    EXPECT_EQ(buffers->vertex_positions.buffer, VK_NULL_HANDLE);
    EXPECT_EQ(buffers->node_positions.count, 0u);
    EXPECT_EQ(buffers->joint_matrices.count, split->chain_count());
}

TEST_F(VulkanTest, SplitSceneOnAnEngineDeviceRecordsStepsAndSharesWholeBuffers) {
    std::string no_device;
    auto engine = EngineDevice::create(no_device);
    if (!no_device.empty()) GTEST_SKIP() << no_device;
    ASSERT_TRUE(engine);
    const EngineDevice& device = *engine;
    const vulkan::ExternalContext context = device.context();

    const Scene scene = two_model_scene();
    const SimulationConfig config = windy_config(Composition::pointer_jumping);
    std::string skip;
    auto reference = create_simulation_or_skip(scene, config, BackendKind::vulkan, skip);
    ASSERT_TRUE(reference);
    const uint64_t window =
        2 * instance_bytes(hmsm::detail::scene_data_of(*reference), device.min_storage_buffer_offset_alignment()) + 7;
    auto created = [&] {
        ForcedWindow forced(window);
        return vulkan::create_simulation(scene, config, context);
    }();
    ASSERT_TRUE(created.ok()) << created.status().message();
    Simulation& sim = *created.value();
    ASSERT_GT(vulkan_of(sim).window_plan().segments().size(), 2u);

    // 5 steps submitted by hmsm, then 15 recorded into the engine's command buffer.
    ASSERT_TRUE(sim.step(5).ok());
    record_steps_on_engine_queue(device, sim, 15);
    if (HasFatalFailure()) return;

    ASSERT_TRUE(reference->step(20).ok());
    for (Output o : kEveryOutput) EXPECT_EQ(read_f32(sim, o), read_f32(*reference, o)) << int(o);

    // The shared outputs are whole buffers, larger than the windows hmsm binds them in.
    auto buffers = vulkan::shared_buffers(sim);
    ASSERT_TRUE(buffers.ok());
    EXPECT_EQ(buffers->vertex_positions.offset, 0u);
    EXPECT_EQ(buffers->vertex_positions.count, sim.vertex_count());
    EXPECT_EQ(buffers->vertex_positions.size, sim.vertex_count() * 16);
    EXPECT_GT(buffers->vertex_positions.size, window);
    EXPECT_EQ(buffers->vertex_normals.size, sim.vertex_count() * 16);
    EXPECT_EQ(buffers->node_positions.size, sim.node_count() * 16);
    EXPECT_EQ(buffers->joint_matrices.offset, 0u);
    EXPECT_EQ(buffers->joint_matrices.stride, 48u);
    EXPECT_EQ(buffers->joint_matrices.count, sim.chain_count());
    EXPECT_EQ(buffers->joint_matrices.size, sim.chain_count() * 48);
    created.value().reset();  // before the engine's device goes away
}

TEST_F(VulkanTest, BufferBeyondItsMemoryHeapIsRefusedBeforeAllocating) {
    std::string skip;
    auto vulkan = create_vulkan_or_skip(skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(vulkan);
    const auto& device = static_cast<detail::vk::VulkanBackend&>(*vulkan).device();
    VkDeviceSize largest_heap = 0;
    for (uint32_t h = 0; h < device.memory_properties().memoryHeapCount; ++h)
        largest_heap = std::max(largest_heap, device.memory_properties().memoryHeaps[h].size);
    std::mt19937 rng(3);
    detail::SceneData data = random_scene_data(rng, {{2, 3, 4}}, {0}, 1);
    // Only the element count matters: the heap is checked before anything is allocated.
    data.total_vertices = data.vertex_capacity = largest_heap / 16 + 1;
    Status s = vulkan->upload(data);
    EXPECT_EQ(s.code(), ErrorCode::out_of_memory);
    EXPECT_NE(s.message().find("vertex_position"), std::string::npos) << s.message();
    // Refused by hmsm before allocating (or, on a driver that already refuses the VkBuffer,
    // by vkCreateBuffer), naming the buffer either way.
    if (s.message().find("vkCreateBuffer") == std::string::npos && s.message().find("cannot create") == std::string::npos)
        EXPECT_NE(s.message().find("memory heap"), std::string::npos) << s.message();
}

}  // namespace
}  // namespace hmsm::test
