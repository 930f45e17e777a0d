// Fades that ended fold in the same switch as the level changes of the call that finds them
// (update_lod, request_instance_lods): one reshape of the state a frame instead of two, with the
// same result as folding first. An instance both folding and asked for a level folds first.
#include "forwarding_backend.h"
#include "simulation_access.h"
#include "test_trees.h"

#include <hmsm/hmsm.h>

#include <gtest/gtest.h>

#include <memory>
#include <vector>

namespace hmsm {
namespace {

/// Counts the calls that move state on the device (a switch within the capacity makes one).
class CountingMoves final : public test::ForwardingBackend {
public:
    using ForwardingBackend::ForwardingBackend;
    Status move_elements(detail::BufferId id, std::span<const detail::ElementMove> moves) override {
        ++calls;
        return ForwardingBackend::move_elements(id, moves);
    }
    Status move_buffers(std::span<const detail::BufferMoves> buffers) override {
        ++calls;
        return ForwardingBackend::move_buffers(buffers);
    }
    int calls = 0;
};

/// Deep trees along x at `xs` starting on `levels` (three levels below the whole tree), fades of
/// 10 steps, bands at 15 and 30 m; stepped in a storm until they sway.
struct Forest {
    std::unique_ptr<Simulation> sim;
    CountingMoves* moves = nullptr;
};

Forest swaying_forest(const std::vector<double>& xs, const std::vector<uint32_t>& levels) {
    Scene scene = single_tree_scene(test::deep_tree(4));
    scene.instances.clear();
    for (size_t k = 0; k < xs.size(); ++k) {
        Instance instance{0, {xs[k], 0.0, 0.0}, 0.1 * double(k), 100.0};
        instance.level = levels[k];
        scene.instances.push_back(instance);
    }
    scene.lod_budgets = {{6, 3, 1}};
    SimulationConfig config = test::windy_config();
    config.backend = BackendKind::cpu64;
    auto backend = detail::create_backend(BackendKind::cpu64);
    EXPECT_TRUE(backend.ok());
    auto counting = std::make_unique<CountingMoves>(std::move(backend).value());
    Forest forest;
    forest.moves = counting.get();
    auto sim = detail::SimulationAccess::create(scene, config, std::move(counting));
    EXPECT_TRUE(sim.ok()) << sim.status().message();
    forest.sim = std::move(sim).value();
    LodBands bands;
    bands.edges = {15.0, 30.0};
    bands.fade_steps = 10;
    EXPECT_TRUE(forest.sim->set_lod_bands(bands).ok());
    EXPECT_TRUE(forest.sim->step(90).ok());
    return forest;
}

/// Eight trees 10 m apart, all on the whole model.
Forest swaying_forest() { return swaying_forest({0, 10, 20, 30, 40, 50, 60, 70}, std::vector<uint32_t>(8, 0)); }

void expect_same(const Simulation& a, const Simulation& b) {
    for (Output output : {Output::chain_angles, Output::chain_rotations, Output::node_positions,
                          Output::vertex_positions}) {
        std::vector<double> x, y;
        ASSERT_TRUE(a.read(output, x).ok());
        ASSERT_TRUE(b.read(output, y).ok());
        ASSERT_EQ(x, y) << "output " << uint32_t(output);
    }
    for (uint64_t i = 0; i < a.instance_count(); ++i)
        EXPECT_EQ(*a.instance_lod(*a.id_of(i)), *b.instance_lod(*b.id_of(i))) << i;
}

// The viewer at x = 0: the trees at 100 and 110 m fade to level 2. After the fades ran out the
// viewer stands at 60 m: the trees at 55 and 65 m (on level 2 from the start) refine at once,
// those at 0 and 10 m begin to fade, and the ended fades fold in the same switch: one move call
// where folding first (request_instance_lods with no levels) and then updating makes two, with
// every output and level the same, then and ten steps later.
TEST(LodFold, EndedFadesSwitchWithUpdateLodsChanges) {
    const std::vector<double> xs = {0, 10, 55, 65, 100, 110};
    const std::vector<uint32_t> levels = {0, 0, 2, 2, 0, 0};
    Forest merged = swaying_forest(xs, levels), twin = swaying_forest(xs, levels);
    for (Forest* f : {&merged, &twin}) {
        ASSERT_EQ(*f->sim->update_lod({0.0, 0.0, 0.0}), 2u);
        ASSERT_EQ(f->sim->fading_instance_count(), 2u);
        ASSERT_TRUE(f->sim->step(10).ok());
    }
    const int merged_before = merged.moves->calls, twin_before = twin.moves->calls;
    ASSERT_EQ(*merged.sim->update_lod({60.0, 0.0, 0.0}), 4u);
    ASSERT_TRUE(twin.sim->request_instance_lods({}, {}).ok());
    ASSERT_EQ(*twin.sim->update_lod({60.0, 0.0, 0.0}), 4u);
    EXPECT_EQ(merged.moves->calls - merged_before, 1);
    EXPECT_EQ(twin.moves->calls - twin_before, 2);
    expect_same(*merged.sim, *twin.sim);
    EXPECT_EQ(*merged.sim->instance_lod(InstanceId{2}), 0u);
    EXPECT_EQ(*merged.sim->instance_lod(InstanceId{4}), 2u);
    EXPECT_EQ(merged.sim->fading_instance_count(), 2u);
    ASSERT_TRUE(merged.sim->step(10).ok());
    ASSERT_TRUE(twin.sim->step(10).ok());
    expect_same(*merged.sim, *twin.sim);
}

// request_instance_lods likewise; an instance whose fade ended and that is asked for another
// level in the same call folds first and is then switched as asked (two move calls).
TEST(LodFold, EndedFadesSwitchWithRequestedLevels) {
    Forest merged = swaying_forest(), twin = swaying_forest();
    const InstanceId near{1}, far{6}, other{3};
    const uint32_t coarse[] = {2, 2};
    for (Forest* f : {&merged, &twin}) {
        ASSERT_TRUE(f->sim->set_instance_lod(other, 2).ok());
        const InstanceId fading[] = {near, far};
        ASSERT_EQ(*f->sim->request_instance_lods(fading, coarse), 2u);
        ASSERT_EQ(f->sim->fading_instance_count(), 2u);
        ASSERT_TRUE(f->sim->step(10).ok());
    }
    const uint32_t zero = 0;
    int before = merged.moves->calls;
    ASSERT_EQ(*merged.sim->request_instance_lods({&other, 1}, {&zero, 1}), 1u);
    EXPECT_EQ(merged.moves->calls - before, 1);
    before = twin.moves->calls;
    ASSERT_TRUE(twin.sim->request_instance_lods({}, {}).ok());
    ASSERT_EQ(*twin.sim->request_instance_lods({&other, 1}, {&zero, 1}), 1u);
    EXPECT_EQ(twin.moves->calls - before, 2);
    expect_same(*merged.sim, *twin.sim);
    EXPECT_EQ(*merged.sim->instance_lod(near), 2u);
    EXPECT_EQ(merged.sim->fading_instance_count(), 0u);

    // Both fade again; once ended, `near` is asked back to level 0 in the call that folds it.
    for (Forest* f : {&merged, &twin}) {
        ASSERT_TRUE(f->sim->set_instance_lod(near, 0).ok());
        ASSERT_TRUE(f->sim->set_instance_lod(far, 0).ok());
        ASSERT_TRUE(f->sim->step(30).ok());
        const InstanceId fading[] = {near, far};
        ASSERT_EQ(*f->sim->request_instance_lods(fading, coarse), 2u);
        ASSERT_TRUE(f->sim->step(10).ok());
    }
    before = merged.moves->calls;
    ASSERT_EQ(*merged.sim->request_instance_lods({&near, 1}, {&zero, 1}), 1u);
    EXPECT_EQ(merged.moves->calls - before, 2);
    ASSERT_TRUE(twin.sim->request_instance_lods({}, {}).ok());
    ASSERT_EQ(*twin.sim->request_instance_lods({&near, 1}, {&zero, 1}), 1u);
    expect_same(*merged.sim, *twin.sim);
    EXPECT_EQ(*merged.sim->instance_lod(near), 0u);
    EXPECT_EQ(*merged.sim->instance_lod(far), 2u);
}

}  // namespace
}  // namespace hmsm
