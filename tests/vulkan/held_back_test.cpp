// Instance changes of a simulation stepped with step() (docs/vulkan.md, "Blocking steps"):
// swap removals, adds and level switches within the capacity are held back and recorded at
// the next submission into one command buffer through the frame ring, so they submit nothing
// of their own; the step submits them; a read submits them first. Results equal the same
// changes submitted one by one as they are made (HMSM_VULKAN_HOLD_BACK=0), bit for bit.
#include "simulation_access.h"
#include "test_trees.h"
#include "vulkan_test_support.h"

#include <cstdlib>

namespace hmsm::test {
namespace {

const detail::vk::VulkanBackend& vulkan_of(const Simulation& sim) {
    return dynamic_cast<const detail::vk::VulkanBackend&>(hmsm::detail::backend_of(sim));
}

/// Frame f's changes: two trees swap-removed and two added (the scene's, moved), two switched
/// by hand, and the viewer moved through the bands.
void change_frame(Simulation& sim, const Scene& scene, uint32_t f) {
    const std::span<const InstanceId> ids = sim.instance_ids();
    const std::vector<InstanceId> gone = {ids[(3 * f + 1) % ids.size()], ids[(5 * f + 2) % ids.size()]};
    std::vector<Instance> added = {scene.instances[f % scene.instances.size()],
                                   scene.instances.back()};  // the deep tree
    for (Instance& t : added) t.origin.x += 40.0 + f;
    ASSERT_TRUE(sim.swap_remove_instances(gone).ok()) << "frame " << f;
    const Status status = sim.add_instances(added);
    ASSERT_TRUE(status.ok()) << "frame " << f << ": " << status.message();
    const std::vector<InstanceId> switched = {sim.instance_ids()[f % 7], sim.instance_ids()[(f + 3) % 7]};
    const std::vector<uint32_t> levels = {f % 4, (f + 2) % 4};
    ASSERT_TRUE(sim.set_instance_lods(switched, levels).ok()) << "frame " << f;
    ASSERT_TRUE(sim.update_lod({6.0 * f, 0.0, 0.0}).ok()) << "frame " << f;
}

TEST_F(VulkanTest, BlockingStepsHoldInstanceChangesBackUntilTheStep) {
    const Scene scene = small_and_deep_with_levels(40);
    SimulationConfig config = windy_config();
    config.instance_layout = InstanceLayout::placed;
    std::string skip;
    auto held = create_simulation_or_skip(scene, config, BackendKind::vulkan, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    setenv("HMSM_VULKAN_HOLD_BACK", "0", 1);
    auto submitted = create_simulation_or_skip(scene, config, BackendKind::vulkan, skip);
    unsetenv("HMSM_VULKAN_HOLD_BACK");
    ASSERT_TRUE(held && submitted);
    LodBands bands;
    bands.edges = {8.0, 16.0, 30.0};
    bands.fade_steps = 3;
    bands.fade_bound_m = 0.0;  // no request reads the state
    for (Simulation* s : {held.get(), submitted.get()}) {
        ASSERT_TRUE(s->reserve_instances(120).ok());
        ASSERT_TRUE(s->set_lod_bands(bands).ok());
        ASSERT_TRUE(s->step(2).ok());
    }
    const detail::vk::VulkanBackend& backend = vulkan_of(*held);
    const detail::vk::VulkanBackend& plain = vulkan_of(*submitted);
    for (uint32_t f = 0; f < 8; ++f) {
        const uint64_t before = backend.submissions(), plain_before = plain.submissions();
        change_frame(*held, scene, f);
        change_frame(*submitted, scene, f);
        if (HasFatalFailure()) return;
        EXPECT_EQ(backend.submissions(), before) << "frame " << f << ": a change submitted";
        EXPECT_GT(backend.held_back_changes(), 0u) << "frame " << f;
        EXPECT_GT(plain.submissions(), plain_before) << "frame " << f;
        EXPECT_EQ(plain.held_back_changes(), 0u) << "frame " << f;
        for (Simulation* s : {held.get(), submitted.get()}) ASSERT_TRUE(s->step(2).ok()) << "frame " << f;
        EXPECT_EQ(backend.held_back_changes(), 0u) << "frame " << f;
    }
    // A read submits what is held first.
    change_frame(*held, scene, 8);
    change_frame(*submitted, scene, 8);
    ASSERT_GT(backend.held_back_changes(), 0u);
    ASSERT_EQ(held->instance_count(), submitted->instance_count());
    EXPECT_EQ(every_output(*held), every_output(*submitted));
    EXPECT_EQ(backend.held_back_changes(), 0u);
    for (Simulation* s : {held.get(), submitted.get()}) ASSERT_TRUE(s->step(3).ok());
    EXPECT_EQ(every_output(*held), every_output(*submitted));
}

}  // namespace
}  // namespace hmsm::test
