// Two simulations of one scene under one wind, for the Vulkan tests of engine recording:
// `recorded` on an engine's device, driven by record_steps into the engine's frames, and
// `reference`, stepped with step() on a Vulkan device of hmsm's own. Results must match bit
// for bit.
#pragma once

#include "engine_device.h"
#include "test_trees.h"

#include "vulkan/step_replay.h"

#include <hmsm/vulkan.h>

#include <gtest/gtest.h>

#include <initializer_list>
#include <memory>
#include <string>
#include <vector>

namespace hmsm::test {

/// Members go in reverse order of destruction: the simulations before the engine's device.
struct RecordedAndReference {
    std::unique_ptr<EngineDevice> engine;
    std::unique_ptr<Simulation> recorded, reference;

    struct Options {
        uint32_t trees = 6;
        Dynamics dynamics = Dynamics::paper;
        std::vector<int32_t> lod_budgets{3, 1};  // of the one model, small_tree()
        bool replay = true;                      // false: recorded without the step replay
        InstanceLayout layout = InstanceLayout::packed;
    };

    /// Small trees on a grid in a wind of strength 6. Empty `skip` and both simulations made,
    /// or `skip` says what is missing (other failures fail the test).
    static RecordedAndReference create(const Options& options, std::string& skip) {
        RecordedAndReference r;
        r.engine = EngineDevice::create(skip);
        if (!skip.empty() || !r.engine) return r;
        SimulationConfig config;
        config.wind.strength = 6.0;
        config.model.dynamics = options.dynamics;
        config.instance_layout = options.layout;
        Scene scene = *grid_scene(small_tree(), options.trees, 5.0, 4);
        if (!options.lod_budgets.empty()) scene.lod_budgets = {options.lod_budgets};
        if (!options.replay) detail::vulkan_set_step_replay(false);
        auto recorded = vulkan::create_simulation(scene, config, r.engine->context());
        if (!options.replay) detail::vulkan_set_step_replay(std::nullopt);
        EXPECT_TRUE(recorded.ok()) << recorded.status().message();
        if (recorded.ok()) r.recorded = std::move(recorded).value();
        r.reference = create_simulation_or_skip(scene, config, BackendKind::vulkan, skip);
        return r;
    }
    static RecordedAndReference create(uint32_t trees, std::string& skip) {
        Options options;
        options.trees = trees;
        return create(options, skip);
    }

    /// One frame: `steps` steps of `recorded` recorded into the engine's frame `f` and
    /// submitted (not waited for), and `reference` stepped as many. The first failure.
    Status step_both(EngineFrames& frames, uint64_t f, uint32_t steps) {
        VkCommandBuffer cmd = frames.begin(f);
        const Status status = vulkan::record_steps(*recorded, cmd, steps);
        frames.submit(f);
        if (!status) return status;
        return reference->step(steps);
    }

    /// `count` frames of an engine with three in flight: change(f) makes the frame's live changes
    /// (to both simulations), step_both runs steps(f) steps, then check(f). Stops at the first
    /// fatal failure; waits for every frame otherwise.
    template <class Change, class Steps, class Check>
    void run_frames(uint32_t count, Change change, Steps steps, Check check) {
        EngineFrames frames(*engine, 3);
        if (::testing::Test::HasFailure()) return;
        for (uint32_t f = 0; f < count; ++f) {
            change(f);
            if (::testing::Test::HasFatalFailure()) return;
            const Status status = step_both(frames, f, steps(f));
            ASSERT_TRUE(status.ok()) << "frame " << f << ": " << status.message();
            check(f);
            if (::testing::Test::HasFatalFailure()) return;
        }
        frames.wait_all();
    }
    /// run_frames with the same live change for both simulations, `steps` steps a frame, and
    /// no check.
    template <class Change>
    void run_frames(uint32_t count, Change change, uint32_t steps) {
        run_frames(
            count, [&](uint32_t f) { for (Simulation* s : {recorded.get(), reference.get()}) change(*s, f); },
            [&](uint32_t) { return steps; }, [](uint32_t) {});
    }
    /// The two run the same models and give the same `outputs`, bit for bit.
    void expect_same(std::initializer_list<Output> outputs) const {
        ASSERT_EQ(recorded->instance_count(), reference->instance_count());
        EXPECT_EQ(recorded->steps_done(), reference->steps_done());
        for (size_t i = 0; i < recorded->instance_count(); ++i)
            EXPECT_EQ(recorded->instances()[i].model, reference->instances()[i].model) << "instance " << i;
        for (Output output : outputs) {
            std::vector<float> a, b;
            ASSERT_TRUE(recorded->read(output, a).ok());
            ASSERT_TRUE(reference->read(output, b).ok());
            EXPECT_EQ(a, b) << "output " << int(output);
        }
    }
};

}  // namespace hmsm::test
