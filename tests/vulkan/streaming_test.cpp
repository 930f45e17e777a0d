// Instances streamed in and out while frames are in flight (docs/vulkan.md, "Streaming
// instances"): on a simulation driven by record_steps, add_instances and remove_instances
// within the reserved capacity are carried by the next recorded command buffer, so hmsm
// neither submits nor waits. Synchronization validation (on in this suite when the layer is
// installed) checks the recorded moves against the frames still running; the results must
// equal the same changes stepped with step() on the Vulkan backend, and agree with cpu64.
#include "engine_device.h"
#include "recorded_pair.h"
#include "simulation_access.h"
#include "test_trees.h"
#include "vulkan_test_support.h"

#include <hmsm/vulkan.h>

namespace hmsm::test {
namespace {

/// The changes before frame `f`: a gust every frame, instances added on some frames and
/// removed on others (from the front, the middle and the back), the wind turned once.
void stream_before_frame(Simulation& s, uint32_t f) {
    Wind wind = s.wind();
    wind.strength = 6.0 + 0.5 * double(f % 4);
    if (f == 6) wind.direction = {0.8, 0.0, 0.6};
    ASSERT_TRUE(s.set_wind(wind).ok());
    if (f % 4 == 1) {
        const Instance added[] = {{0, {10.0 + f, 0.0, 3.0}, 0.3 * f}, {0, {-4.0, 0.0, 2.0 * f}, 1.0}};
        ASSERT_TRUE(s.add_instances(added).ok());
    }
    if (f % 4 == 3) {
        const uint64_t gone[] = {0, s.instance_count() / 2};
        ASSERT_TRUE(s.remove_instances(gone).ok());
    }
    if (f == 8) {
        const uint64_t last[] = {s.instance_count() - 1};
        ASSERT_TRUE(s.remove_instances(last).ok());
    }
}

/// A simulation on the engine's device, driven by record_steps in the tests, and a reference
/// on hmsm's own Vulkan device that takes the same changes through step(); both of a grid of
/// small trees in a steady wind.
class Streaming : public VulkanTest {
protected:
    /// Creates both on a grid of `trees` trees; skips where there is no device. The test
    /// returns when IsSkipped() or HasFatalFailure().
    void create(uint32_t trees) {
        std::string no_device;
        engine_ = EngineDevice::create(no_device);
        if (!no_device.empty()) GTEST_SKIP() << no_device;
        ASSERT_TRUE(engine_);
        config_.wind.strength = 6.0;
        scene_ = *grid_scene(small_tree(), trees, 5.0, 4);
        auto recorded = vulkan::create_simulation(scene_, config_, engine_->context());
        ASSERT_TRUE(recorded.ok()) << recorded.status().message();
        recorded_ = std::move(recorded).value();
        std::string skip;
        reference_ = create_simulation_or_skip(scene_, config_, BackendKind::vulkan, skip);
        ASSERT_TRUE(reference_);
        backend_ = &dynamic_cast<const detail::vk::VulkanBackend&>(detail::backend_of(*recorded_));
    }
    /// The simulations go before the engine's device, and before the validation messages are
    /// checked.
    void TearDown() override {
        recorded_.reset();
        reference_.reset();
        engine_.reset();
        VulkanTest::TearDown();
    }

    std::unique_ptr<EngineDevice> engine_;
    SimulationConfig config_;
    Scene scene_;
    std::unique_ptr<Simulation> recorded_, reference_;
    const detail::vk::VulkanBackend* backend_ = nullptr;
};

TEST_F(Streaming, StreamedInstancesTravelWithTheRecordedFrames) {
    create(4);
    if (IsSkipped() || HasFatalFailure()) return;
    Simulation& sim = *recorded_;
    Simulation* reference = reference_.get();
    SimulationConfig exact = config_;
    exact.backend = BackendKind::cpu64;
    auto oracle = Simulation::create(scene_, exact);
    ASSERT_TRUE(oracle.ok()) << oracle.status().message();
    for (Simulation* s : {&sim, reference, oracle.value().get()}) ASSERT_TRUE(s->reserve_instances(12).ok());
    const detail::vk::VulkanBackend& backend = *backend_;

    constexpr uint32_t kFrames = 12;
    {
        EngineFrames frames(*engine_, 3);
        if (HasFailure()) return;
        // The first frame makes the simulation one driven by record_steps.
        VkCommandBuffer first = frames.begin(0);
        ASSERT_TRUE(vulkan::record_steps(sim, first, 2).ok());
        frames.submit(0);
        ASSERT_TRUE(reference->step(2).ok());
        ASSERT_TRUE(oracle.value()->step(2).ok());
        const uint64_t submissions = backend.submissions();
        const vulkan::SharedBuffers buffers = *vulkan::shared_buffers(sim);
        for (uint32_t f = 1; f < kFrames; ++f) {
            for (Simulation* s : {&sim, reference, oracle.value().get()}) stream_before_frame(*s, f);
            if (HasFatalFailure()) return;
            if (f % 4 == 1 || f % 4 == 3) EXPECT_GT(backend.held_back_changes(), 0u) << "frame " << f;
            VkCommandBuffer cmd = frames.begin(f);
            const Status status = vulkan::record_steps(sim, cmd, 2);
            frames.submit(f);
            ASSERT_TRUE(status.ok()) << "frame " << f << ": " << status.message();
            EXPECT_EQ(backend.held_back_changes(), 0u);
            ASSERT_TRUE(reference->step(2).ok());
            ASSERT_TRUE(oracle.value()->step(2).ok());
        }
        // hmsm neither submitted nor waited, and the buffers the engine draws from stayed.
        EXPECT_EQ(backend.submissions(), submissions);
        EXPECT_EQ(vulkan::shared_buffers(sim)->joint_matrices.buffer, buffers.joint_matrices.buffer);
        frames.wait_all();
    }
    ASSERT_EQ(sim.instance_count(), reference->instance_count());
    EXPECT_EQ(sim.steps_done(), reference->steps_done());
    for (Output output : {Output::node_positions, Output::vertex_positions, Output::joint_matrices}) {
        std::vector<float> a, b;
        std::vector<double> exact_values;
        ASSERT_TRUE(sim.read(output, a).ok());
        ASSERT_TRUE(reference->read(output, b).ok());
        EXPECT_EQ(a, b) << "output " << int(output);
        if (output == Output::joint_matrices) continue;
        ASSERT_TRUE(oracle.value()->read(output, exact_values).ok());
        EXPECT_LT(relative_difference(std::vector<double>(a.begin(), a.end()), exact_values), 1e-4)
            << "output " << int(output);
    }
}

TEST_F(Streaming, GrowthPastTheCapacityWhileRecordingSubmitsAndStillMatches) {
    create(2);
    if (IsSkipped() || HasFatalFailure()) return;
    Simulation& sim = *recorded_;
    Simulation* reference = reference_.get();
    const detail::vk::VulkanBackend& backend = *backend_;
    {
        EngineFrames frames(*engine_, 3);
        if (HasFailure()) return;
        for (uint32_t f = 0; f < 6; ++f) {
            if (f == 3) {
                // Past the capacity: the scene is uploaded anew, which submits and waits.
                std::vector<Instance> many(6, Instance{0, {20.0, 0.0, 0.0}, 0.5});
                for (size_t k = 0; k < many.size(); ++k) many[k].origin.z = 4.0 * double(k);
                const uint64_t submissions = backend.submissions();
                ASSERT_TRUE(sim.add_instances(many).ok());
                ASSERT_TRUE(reference->add_instances(many).ok());
                EXPECT_GT(backend.submissions(), submissions);
            }
            VkCommandBuffer cmd = frames.begin(f);
            const Status status = vulkan::record_steps(sim, cmd, 3);
            frames.submit(f);
            ASSERT_TRUE(status.ok()) << status.message();
            ASSERT_TRUE(reference->step(3).ok());
        }
        frames.wait_all();
    }
    EXPECT_EQ(sim.instance_count(), reference->instance_count());
    std::vector<float> a, b;
    ASSERT_TRUE(sim.read(Output::vertex_positions, a).ok());
    ASSERT_TRUE(reference->read(Output::vertex_positions, b).ok());
    EXPECT_EQ(a, b);
}

// Level switches while the engine records: each switch reads the switched instances' state,
// and its moves, writes and pose travel in the next recorded command buffer; the result equals
// the same switches stepped with step() on the Vulkan backend.
TEST_F(VulkanTest, LevelSwitchesTravelWithTheRecordedFrames) {
    std::string skip;
    RecordedAndReference pair = RecordedAndReference::create(6, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(pair.recorded && pair.reference);
    Simulation &sim = *pair.recorded, &reference = *pair.reference;
    const auto& backend = dynamic_cast<const detail::vk::VulkanBackend&>(detail::backend_of(sim));
    {
        EngineFrames frames(*pair.engine, 3);
        if (HasFailure()) return;
        ASSERT_TRUE(pair.step_both(frames, 0, 2).ok());
        for (uint32_t f = 1; f < 9; ++f) {
            const InstanceId ids[] = {InstanceId(0), InstanceId(2), InstanceId(3), InstanceId(5)};
            const uint32_t levels[] = {f % 3, (f + 1) % 3, (2 * f) % 3, (f + 2) % 3};
            for (Simulation* s : {&sim, &reference}) ASSERT_TRUE(s->set_instance_lods(ids, levels).ok());
            EXPECT_GT(backend.held_back_changes(), 0u) << "frame " << f;
            const Status status = pair.step_both(frames, f, 2);
            ASSERT_TRUE(status.ok()) << "frame " << f << ": " << status.message();
            EXPECT_EQ(backend.held_back_changes(), 0u);
        }
        frames.wait_all();
    }
    pair.expect_same({Output::node_positions, Output::vertex_positions, Output::joint_matrices});
}

// A coarsening request fades in pass 2 on the device, with no host round trip per step: the
// fades run inside recorded steps, and record_steps switches the fades that are over before its
// recording, exactly as step() does with the same requests on a plain simulation.
TEST_F(VulkanTest, RecordedStepsFadeAsStepDoes) {
    std::string skip;
    RecordedAndReference pair = RecordedAndReference::create(5, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(pair.recorded && pair.reference);
    Simulation &sim = *pair.recorded, &reference = *pair.reference;
    LodBands bands;
    bands.edges = {100.0};
    bands.fade_steps = 4;  // two frames of two steps
    ASSERT_TRUE(sim.set_lod_bands(bands).ok());
    ASSERT_TRUE(reference.set_lod_bands(bands).ok());
    {
        EngineFrames frames(*pair.engine, 3);
        if (HasFailure()) return;
        for (uint32_t f = 0; f < 6; ++f) {
            if (f == 2) {
                const InstanceId ids[] = {InstanceId(1), InstanceId(4)};
                const uint32_t levels[] = {2, 1};
                for (Simulation* s : {&sim, &reference}) {
                    auto requested = s->request_instance_lods(ids, levels);
                    ASSERT_TRUE(requested.ok()) << requested.status().message();
                    ASSERT_EQ(s->fading_instance_count(), 2u) << "the trees sway: their switches fade";
                }
            }
            const Status status = pair.step_both(frames, f, 2);
            ASSERT_TRUE(status.ok()) << "frame " << f << ": " << status.message();
            EXPECT_EQ(sim.fading_instance_count(), f == 2 || f == 3 ? 2u : 0u) << "frame " << f;
        }
        frames.wait_all();
    }
    EXPECT_EQ(*sim.instance_lod(InstanceId(1)), 2u);
    EXPECT_EQ(*sim.instance_lod(InstanceId(4)), 1u);
    pair.expect_same({Output::node_positions, Output::joint_matrices});
}

// Level requests while the engine records read no state: a tree just added (at rest) fades to
// the coarser level asked for, where a simulation stepped with step() measures it at rest and
// switches at once; the request neither submits nor waits, and the fade ends in a recording.
TEST_F(VulkanTest, LevelRequestsWhileRecordingReadNothing) {
    std::string skip;
    RecordedAndReference pair = RecordedAndReference::create(4, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(pair.recorded && pair.reference);
    Simulation &sim = *pair.recorded, &reference = *pair.reference;
    const auto& backend = dynamic_cast<const detail::vk::VulkanBackend&>(detail::backend_of(sim));
    LodBands bands;
    bands.edges = {100.0};
    bands.fade_steps = 4;  // two frames of two steps
    for (Simulation* s : {&sim, &reference}) ASSERT_TRUE(s->set_lod_bands(bands).ok());
    {
        EngineFrames frames(*pair.engine, 3);
        if (HasFailure()) return;
        ASSERT_TRUE(pair.step_both(frames, 0, 2).ok());
        const Instance still[] = {{0, {30.0, 0.0, 30.0}, 0.5}};
        const uint32_t coarser[] = {2};
        InstanceId added[2] = {};  // in sim, in reference
        for (int k = 0; k < 2; ++k) {
            Simulation& s = k == 0 ? sim : reference;
            ASSERT_TRUE(s.add_instances(still, std::span<InstanceId>(&added[k], 1)).ok());
            const uint64_t submitted = backend.submissions();
            ASSERT_TRUE(s.request_instance_lods({&added[k], 1}, coarser).ok());
            if (k == 0) EXPECT_EQ(backend.submissions(), submitted) << "the request read the state";
        }
        EXPECT_EQ(sim.fading_instance_count(), 1u) << "recording: the tree at rest fades";
        EXPECT_EQ(reference.fading_instance_count(), 0u) << "step(): measured at rest, switched at once";
        EXPECT_EQ(*reference.instance_lod(added[1]), 2u);
        for (uint32_t f = 1; f < 4; ++f) ASSERT_TRUE(pair.step_both(frames, f, 2).ok()) << "frame " << f;
        frames.wait_all();
        EXPECT_EQ(sim.fading_instance_count(), 0u);
        EXPECT_EQ(*sim.instance_lod(added[0]), 2u);
    }
}

// Many trees switched, added and removed at once in the placed layout while the engine records:
// each level switch's pattern copies and each write of ranges are held back as one change and
// recorded as range-copy dispatches in the frame's command buffer (tables and values staged in
// the frame's ring slot), not as a ring copy or a move per range, or submitted as one where a
// read comes first; the results equal the same changes stepped with step(), under
// synchronization validation with three frames in flight.
TEST_F(VulkanTest, ManyRangesAndPatternCopiesTravelAsDispatches) {
    RecordedAndReference::Options options;
    options.trees = 90;
    options.layout = InstanceLayout::placed;
    std::string skip;
    RecordedAndReference pair = RecordedAndReference::create(options, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(pair.recorded && pair.reference);
    Simulation &sim = *pair.recorded, &reference = *pair.reference;
    const auto& backend = dynamic_cast<const detail::vk::VulkanBackend&>(detail::backend_of(sim));
    for (Simulation* s : {&sim, &reference}) ASSERT_TRUE(s->reserve_instances(400).ok());
    uint64_t dispatches = 0, ranges = 0;
    size_t most_held_back = 0;
    {
        EngineFrames frames(*pair.engine, 3);
        if (HasFailure()) return;
        ASSERT_TRUE(pair.step_both(frames, 0, 1).ok());
        for (uint32_t f = 1; f < 8; ++f) {
            if (f % 2 == 1) {  // every tree to another level
                std::vector<InstanceId> ids(sim.instance_ids().begin(), sim.instance_ids().end());
                std::vector<uint32_t> levels;
                for (size_t k = 0; k < ids.size(); ++k) levels.push_back(uint32_t((k + f) % 3));
                for (Simulation* s : {&sim, &reference}) ASSERT_TRUE(s->set_instance_lods(ids, levels).ok());
                ranges += ids.size();
            }
            if (f % 3 == 1) {  // seventy trees in
                std::vector<Instance> added;
                for (uint32_t k = 0; k < 70; ++k)
                    added.push_back({0, {-20.0 - 3.0 * k, 0.0, 4.0 + f}, 0.1 * k, 1.0, 0.0, true, k % 3});
                for (Simulation* s : {&sim, &reference}) ASSERT_TRUE(s->add_instances(added).ok());
                ranges += added.size();
            }
            if (f % 3 == 2) {  // sixty-six out, from everywhere
                std::vector<InstanceId> gone;
                for (size_t k = 0; k < 66; ++k) gone.push_back(sim.instance_ids()[k * sim.instance_count() / 66]);
                for (Simulation* s : {&sim, &reference}) ASSERT_TRUE(s->swap_remove_instances(gone).ok());
                ranges += gone.size();
            }
            most_held_back = std::max(most_held_back, backend.held_back_changes());
            if (f == 5) {  // a read submits what is held back, through the backend's own submissions
                frames.wait_all();
                std::vector<float> a, b;
                ASSERT_TRUE(sim.read(Output::joint_matrices, a).ok());
                ASSERT_TRUE(reference.read(Output::joint_matrices, b).ok());
                EXPECT_EQ(a, b);
                EXPECT_EQ(backend.held_back_changes(), 0u);
            }
            const uint64_t dispatched = backend.range_copy_dispatches();
            const Status status = pair.step_both(frames, f, 1);
            ASSERT_TRUE(status.ok()) << "frame " << f << ": " << status.message();
            EXPECT_EQ(backend.held_back_changes(), 0u);
            dispatches += backend.range_copy_dispatches() - dispatched;
        }
        frames.wait_all();
    }
    std::printf("%llu ranges changed: %llu range-copy dispatches, at most %zu changes held back\n",
                (unsigned long long)ranges, dispatches, most_held_back);
    EXPECT_GT(dispatches, 0u);
    EXPECT_LT(most_held_back, 20u) << "a change held back per range";
    pair.expect_same({Output::node_positions, Output::joint_matrices});
}

// A swap removal of many trees near the front of a packed forest while the engine records:
// each hole takes a tree from the back, so every buffer's moves lie apart from their sources,
// and its 65 moves are recorded as one pattern-copy dispatch (its table staged in the frame's
// ring slot) rather than as a copy command of 65 regions; a removal of a few still goes as
// copy regions. The results equal the same removals stepped with step(), under
// synchronization validation with three frames in flight.
TEST_F(VulkanTest, ManySwapRemovalMovesTravelAsADispatch) {
    RecordedAndReference::Options options;
    options.trees = 200;
    options.lod_budgets.clear();
    std::string skip;
    RecordedAndReference pair = RecordedAndReference::create(options, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(pair.recorded && pair.reference);
    const auto& backend = dynamic_cast<const detail::vk::VulkanBackend&>(detail::backend_of(*pair.recorded));
    uint64_t dispatched = 0, copied = 0;
    pair.run_frames(
        4,
        [&](uint32_t f) {
            dispatched = backend.range_copy_dispatches();
            copied = backend.moves_recorded_as_copies();
            std::vector<InstanceId> gone;  // every other one of the first 140, then the first three
            const std::span<const InstanceId> ids = pair.recorded->instance_ids();
            if (f == 1)
                for (size_t k = 0; k < 140; k += 2) gone.push_back(ids[k]);
            if (f == 2) gone.assign(ids.begin(), ids.begin() + 3);
            for (Simulation* s : {pair.recorded.get(), pair.reference.get()})
                ASSERT_TRUE(s->swap_remove_instances(gone).ok()) << "frame " << f;
        },
        [](uint32_t) { return 2u; },
        [&](uint32_t f) {
            if (f == 1) {
                EXPECT_EQ(backend.moves_recorded_as_copies(), copied) << "65 moves of a buffer as copy regions";
                EXPECT_GT(backend.range_copy_dispatches(), dispatched) << "no pattern copy of the moves";
            }
            if (f == 2) EXPECT_GT(backend.moves_recorded_as_copies(), copied) << "3 moves of a buffer not as copy regions";
        });
    EXPECT_EQ(pair.recorded->instance_count(), 127u);
    pair.expect_same({Output::node_positions, Output::joint_matrices, Output::vertex_positions});
}

}  // namespace
}  // namespace hmsm::test
