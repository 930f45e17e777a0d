// dispatch_batches (src/step_program.h): the runs of a step program that one launch may run
// together, for a scene whose instances alternate between models (one group per instance).
#include "simulation_access.h"
#include "test_compositions.h"
#include "test_trees.h"

#include "step_program.h"

#include <gtest/gtest.h>

#include <set>
#include <utility>

using namespace hmsm;

namespace {

/// Seven instances alternating between a deep tree and a small tree: seven groups.
Scene alternating_scene() {
    Scene scene;
    scene.models = {test::deep_tree(5), test::small_tree()};
    scene.model_names = {"deep", "small"};
    for (uint32_t i = 0; i < 7; ++i) scene.instances.push_back(Instance{.model = i % 2, .origin = Vec3(4.0 * i, 0, 0)});
    return scene;
}

/// Checks the runs of `program`: they cover it in order, each dispatch of a run has the pass,
/// kind, round and halves of the run's first and a group of its own, and two neighbouring runs
/// could not be one. Returns the number of runs.
size_t check_batches(const std::vector<detail::Dispatch>& program) {
    const auto runs = detail::dispatch_batches(program);
    size_t covered = 0;
    for (size_t r = 0; r < runs.size(); ++r) {
        const auto& run = runs[r];
        EXPECT_FALSE(run.empty());
        EXPECT_EQ(run.data(), program.data() + covered) << "run " << r << " is not the next part of the program";
        covered += run.size();
        std::set<uint32_t> groups;
        for (const auto& d : run) {
            EXPECT_EQ(d.pass, run[0].pass);
            EXPECT_EQ(d.constants.kind, run[0].constants.kind);
            EXPECT_EQ(d.constants.round, run[0].constants.round);
            EXPECT_EQ(d.constants.src_half, run[0].constants.src_half);
            EXPECT_EQ(d.constants.dst_half, run[0].constants.dst_half);
            EXPECT_TRUE(groups.insert(d.constants.instance_begin).second) << "a group twice in run " << r;
        }
        if (r > 0) {
            const auto& last = runs[r - 1].back();
            const auto& next = run.front();
            const bool same = last.pass == next.pass && last.constants.kind == next.constants.kind &&
                              last.constants.round == next.constants.round &&
                              last.constants.src_half == next.constants.src_half &&
                              last.constants.dst_half == next.constants.dst_half;
            EXPECT_TRUE(!same || next.constants.instance_begin <= last.constants.instance_begin)
                << "runs " << r - 1 << " and " << r << " could be one";
        }
    }
    EXPECT_EQ(covered, program.size());
    return runs.size();
}

}  // namespace

TEST(DispatchBatches, EmptyProgramHasNoRuns) { EXPECT_TRUE(detail::dispatch_batches({}).empty()); }

class DispatchBatchesByComposition : public ::testing::TestWithParam<test::TestComposition> {};

TEST_P(DispatchBatchesByComposition, ManyGroupsTakeAsManyRunsAsOne) {
    SimulationConfig config;
    config.backend = BackendKind::cpu;
    auto forest = test::create_simulation(alternating_scene(), config, GetParam());
    ASSERT_TRUE(forest.ok()) << forest.status().message();
    ASSERT_EQ(detail::scene_data_of(**forest).groups.size(), 7u);
    const auto& program = detail::step_program_of(**forest);
    const size_t runs = check_batches(program);
    EXPECT_LT(runs, program.size());

    // One deep tree alone: at least as many runs (the small tree's levels end earlier).
    auto lone = test::create_simulation(single_tree_scene(test::deep_tree(5)), config, GetParam());
    ASSERT_TRUE(lone.ok()) << lone.status().message();
    EXPECT_EQ(runs, check_batches(detail::step_program_of(**lone)));
}

INSTANTIATE_TEST_SUITE_P(EveryComposition, DispatchBatchesByComposition,
                         ::testing::ValuesIn(test::kEveryComposition));

TEST(DispatchBatches, RoundsAndLevelsOfOneGroupStayApart) {
    // One group: every dispatch of a hierarchical pass depends on the one before it.
    SimulationConfig config;
    config.backend = BackendKind::cpu;
    for (test::TestComposition composition : test::kEveryComposition) {
        auto sim = test::create_simulation(single_tree_scene(test::deep_tree(5)), config, composition);
        ASSERT_TRUE(sim.ok()) << sim.status().message();
        const auto& program = detail::step_program_of(**sim);
        EXPECT_EQ(detail::dispatch_batches(program).size(), program.size());
    }
}
