// The step program (src/step_program.cpp): which dispatches one step issues for each way of
// composing passes 3 and 5.
#include "simulation_access.h"
#include "test_compositions.h"
#include "test_trees.h"

#include "backend.h"
#include "step_program.h"

#ifdef HMSM_HAVE_CUDA
#include "agreement/cuda_emulation_backend.h"
#endif

#include <gtest/gtest.h>

#include <algorithm>

using namespace hmsm;

namespace {

std::unique_ptr<Simulation> cpu_simulation(const Scene& scene, test::TestComposition composition,
                                           double wind_gain = 0.2) {
    SimulationConfig config;
    config.backend = BackendKind::cpu;
    config.parameters.wind_gain = wind_gain;
    auto sim = test::create_simulation(scene, config, composition);
    EXPECT_TRUE(sim.ok()) << sim.status().message();
    return sim.ok() ? std::move(sim).value() : nullptr;
}

std::vector<detail::Dispatch> dispatches_of(const Simulation& sim, Pass pass) {
    std::vector<detail::Dispatch> out;
    for (const auto& d : hmsm::detail::step_program_of(sim))
        if (d.pass == pass) out.push_back(d);
    return out;
}


}  // namespace

TEST(StepProgram, RoundsInOneDispatchGiveOneDispatchPerPass) {
    auto sim = cpu_simulation(single_tree_scene(test::deep_tree(6)), test::kJumpingInDispatch);
    ASSERT_TRUE(sim);
    ASSERT_EQ(sim->jump_rounds(), 3u);
    EXPECT_EQ(hmsm::detail::step_program_of(*sim).size(), kPassCount);  // the seven passes, one dispatch each
    for (Pass pass : {Pass::compose, Pass::root_positions}) {
        auto d = dispatches_of(*sim, pass);
        ASSERT_EQ(d.size(), 1u);
        EXPECT_EQ(d[0].constants.kind, HMSM_DISPATCH_JUMP_ROUNDS_IN_DISPATCH);
        EXPECT_EQ(d[0].constants.round, 3u);  // every round
        const detail::LaunchShape shape = detail::launch_shape(d[0]);
        EXPECT_EQ(shape.workgroups, 1u);  // one workgroup per instance
        EXPECT_EQ(shape.workgroup_size, gpu::rounds_workgroup_size(sim->hierarchy(0).chains.size()));
    }
}

TEST(StepProgram, GridOfInstancesGetsOneWorkgroupPerInstance) {
    auto sim = cpu_simulation(*grid_scene(test::small_tree(), 7, 6.0, 42), test::kJumpingInDispatch);
    ASSERT_TRUE(sim);
    auto d = dispatches_of(*sim, Pass::compose);
    ASSERT_EQ(d.size(), 1u);
    EXPECT_EQ(detail::launch_shape(d[0]).workgroups, 7u);
}

/// The kinds pointer_jumping gives compose and root_positions dispatches for `instances` of `tree`.
static std::vector<uint32_t> default_kinds(const TreeModel& tree, uint32_t instances) {
    auto scene = grid_scene(tree, instances, 6.0, 42);
    EXPECT_TRUE(scene.ok());
    auto sim = cpu_simulation(*scene, Composition::pointer_jumping);
    std::vector<uint32_t> kinds;
    if (!sim) return kinds;
    for (Pass pass : {Pass::compose, Pass::root_positions})
        for (const auto& d : dispatches_of(*sim, pass)) kinds.push_back(d.constants.kind);
    return kinds;
}

TEST(StepProgram, PointerJumpingRunsRoundsInOneDispatchForForestsAndSmallModels) {
    const std::vector<uint32_t> in_dispatch(2, HMSM_DISPATCH_JUMP_ROUNDS_IN_DISPATCH);
    // Models of at most 512 chains: always (one workgroup covers all chains in one go).
    EXPECT_EQ(default_kinds(test::small_tree(), 1), in_dispatch);
    EXPECT_EQ(default_kinds(test::broom(512), 1), in_dispatch);
    // Larger models: from 64 instances up; with fewer, one dispatch per round (a depth-1 broom
    // has one round).
    const std::vector<uint32_t> per_round(2, HMSM_DISPATCH_JUMP_ROUND);
    EXPECT_EQ(default_kinds(test::broom(513), 1), per_round);
    EXPECT_EQ(default_kinds(test::broom(1100), 63), per_round);
    EXPECT_EQ(default_kinds(test::broom(1100), 64), in_dispatch);
}

TEST(StepProgram, PerRoundAndLevelByLevelIssueOneDispatchPerRoundOrLevel) {
    const Scene scene = single_tree_scene(test::deep_tree(6));
    auto per_round = cpu_simulation(scene, test::kJumpingPerRound);
    auto level = cpu_simulation(scene, Composition::level_by_level);
    ASSERT_TRUE(per_round && level);
    for (Pass pass : {Pass::compose, Pass::root_positions}) {
        auto rounds = dispatches_of(*per_round, pass);
        ASSERT_EQ(rounds.size(), 3u);
        for (uint32_t r = 0; r < rounds.size(); ++r) {
            EXPECT_EQ(rounds[r].constants.kind, HMSM_DISPATCH_JUMP_ROUND);
            EXPECT_EQ(rounds[r].constants.round, r);
            EXPECT_EQ(rounds[r].constants.dst_half, r & 1);
        }
        const auto levels = dispatches_of(*level, pass);
        EXPECT_EQ(levels.size(), 7u);  // depths 0..6
        for (const auto& d : levels) {
            EXPECT_EQ(d.constants.kind, HMSM_DISPATCH_LEVEL);
            EXPECT_EQ(d.constants.round, 0u);  // round means only a pointer-jumping round
        }
    }
    EXPECT_EQ(hmsm::detail::step_program_of(*per_round).size(), kPassCount - 2 + 2 * 3);
}

// Path walk: each walk pair of the pass table in one dispatch of its leader, a thread per chain
// (per node for node_relative with node_world): a step of one tree is four dispatches, the fewest
// of any composition, and joints only two. The poses are level by level's bit for bit (the walk
// runs its operations in its order).
TEST(StepProgram, PathWalkRunsThePairsInOneDispatchEachAndEqualsLevelByLevelBitwise) {
    const Scene scene = single_tree_scene(test::deep_tree(6), {2, 0, -1}, 0.4);
    const double storm = 15.0;  // wind gain: large angles
    auto walk = cpu_simulation(scene, Composition::path_walk, storm);
    ASSERT_TRUE(walk);
    const auto& program = hmsm::detail::step_program_of(*walk);
    ASSERT_EQ(program.size(), 4u);
    const Pass leaders[] = {Pass::wind_force, Pass::compose, Pass::node_relative, Pass::contour};
    for (size_t i = 0; i < 4; ++i) {
        EXPECT_EQ(program[i].pass, leaders[i]);
        const uint64_t per_instance = leaders[i] == Pass::node_relative ? walk->node_count()
                                      : leaders[i] == Pass::contour     ? program[i].constants.model_vertex_count
                                                                        : walk->hierarchy(0).chains.size();
        EXPECT_EQ(program[i].constants.element_count, per_instance);
        if (leaders[i] != Pass::contour) {
            EXPECT_TRUE(hmsm::detail::runs_path_walk(program[i]));
            EXPECT_EQ(program[i].constants.round, 0u);
        }
    }
    EXPECT_EQ(program[0].constants.kind, HMSM_DISPATCH_WIND_PAIR);
    EXPECT_EQ(program[2].constants.kind, HMSM_DISPATCH_NODE_PAIR);
    EXPECT_EQ(program[3].constants.kind, HMSM_DISPATCH_CONTOUR_SEPARATE);
    EXPECT_EQ(program[1].constants.dst_half, HMSM_FINAL_HALF(walk->jump_rounds()));
    // A walk step stores no intermediate: the wind pair only the angles, the walk only the joint
    // matrices, which are the pose (T comes from the angles), the node pair only the world
    // positions; the wind and node pairs read the pose from the joint matrices.
    using hmsm::detail::BufferId;
    auto bits = [](std::initializer_list<BufferId> ids) {
        uint32_t b = 0;
        for (BufferId id : ids) b |= 1u << uint32_t(id);
        return b;
    };
    EXPECT_EQ(hmsm::detail::dispatch_writes(program[0]), bits({BufferId::chain_state}));
    EXPECT_EQ(hmsm::detail::dispatch_writes(program[1]), bits({BufferId::joint_matrix}));
    for (size_t i : {0u, 2u, 3u}) {
        EXPECT_NE(hmsm::detail::dispatch_reads(program[i]) & bits({BufferId::joint_matrix}), 0u) << i;
        EXPECT_EQ(hmsm::detail::dispatch_reads(program[i]) & bits({BufferId::chain_rotation, BufferId::chain_origin}),
                  0u) << i;
    }
    EXPECT_EQ(hmsm::detail::dispatch_reads(program[1]) &
                  bits({BufferId::chain_local, BufferId::chain_force, BufferId::node_relative}), 0u);
    EXPECT_EQ(hmsm::detail::dispatch_writes(program[2]), bits({BufferId::node_world}));
    EXPECT_EQ(hmsm::detail::dispatch_passes(program[1]),
              (1u << uint32_t(Pass::compose)) | (1u << uint32_t(Pass::root_positions)));
    // Also a tree deeper than the walk records hold (HMSM_WALK_PATH_CAPACITY), and a forest of
    // it, whose program has the GPU walk follow chain_parent up instead of reading the records.
    const Scene deeper = single_tree_scene(test::deep_tree(HMSM_WALK_PATH_CAPACITY + 3), {0, 0, 1}, -0.3);
    const Scene forest = *grid_scene(test::deep_tree(HMSM_WALK_PATH_CAPACITY + 3), 20, 9.0, 3);
    EXPECT_EQ(program[1].constants.kind, HMSM_DISPATCH_POSE_WALK_FROM_RECORDS);  // one instance: the records
    auto walk_forest = cpu_simulation(forest, Composition::path_walk, storm);
    ASSERT_TRUE(walk_forest);
    EXPECT_EQ(hmsm::detail::step_program_of(*walk_forest)[1].constants.kind, HMSM_DISPATCH_POSE_WALK);
    for (const Scene* s : {&scene, &deeper, &forest}) {
        auto w = cpu_simulation(*s, Composition::path_walk, storm);
        auto l = cpu_simulation(*s, Composition::level_by_level, storm);
        auto at_rest = cpu_simulation(*s, Composition::level_by_level, storm);
        ASSERT_TRUE(w && l && at_rest);
        ASSERT_TRUE(w->step(300).ok());
        ASSERT_TRUE(l->step(300).ok());
        for (Output o : {Output::chain_rotations, Output::chain_origins, Output::joint_matrices,
                         Output::node_positions, Output::vertex_positions}) {
            std::vector<double> a, b, rest;
            ASSERT_TRUE(w->read(o, a).ok());
            ASSERT_TRUE(l->read(o, b).ok());
            ASSERT_TRUE(at_rest->read(o, rest).ok());
            EXPECT_EQ(a, b) << "output " << int(o);
            double moved = 0.0;
            for (size_t i = 0; i < a.size(); ++i) moved = std::max(moved, std::abs(rest[i] - b[i]));
            EXPECT_GT(moved, 1e-3) << "output " << int(o);  // the wind bent the tree
        }
    }
}

// Joints only: the walk needs no node_relative, so a step is the two walk dispatches; programs
// of some passes (the rest pose from integrate on) run the passes apart from their leader alone.
// Without vertex outputs the layout holds no vertex (a joints-only forest is not bounded by
// mesh vertices it never produces), and the joints move exactly as with every output.
TEST(StepProgram, ALayoutWithoutVertexOutputsHoldsNoVertex) {
    Scene scene = single_tree_scene(test::deep_tree(4));
    scene.instances.push_back(scene.instances[0]);
    scene.instances.back().origin = Vec3(4.0, 0.0, 0.0);
    SimulationConfig config;
    config.backend = BackendKind::cpu;
    std::vector<float> expected;
    for (Outputs outputs : {Outputs::all, Outputs::joints_and_nodes, Outputs::joints}) {
        config.outputs = outputs;
        auto sim = Simulation::create(scene, config);
        ASSERT_TRUE(sim.ok()) << sim.status().message();
        const auto& data = hmsm::detail::scene_data_of(**sim);
        EXPECT_GT((*sim)->vertex_count(), 0u);  // the meshes' vertices, produced or not
        EXPECT_EQ(data.total_vertices, outputs == Outputs::all ? (*sim)->vertex_count() : 0u);
        EXPECT_EQ(data.vertex_capacity, data.total_vertices);
        ASSERT_TRUE((*sim)->step(20).ok());
        std::vector<float> joints;
        ASSERT_TRUE((*sim)->read(Output::joint_matrices, joints).ok());
        if (expected.empty()) expected = joints;
        EXPECT_EQ(joints, expected);
    }
}

TEST(StepProgram, PathWalkProgramsFollowTheOutputsAndThePassesAsked) {
    const Scene scene = single_tree_scene(test::deep_tree(4));
    SimulationConfig config;
    config.backend = BackendKind::cpu;
    config.composition = Composition::path_walk;
    config.outputs = Outputs::joints;
    auto joints = Simulation::create(scene, config);
    ASSERT_TRUE(joints.ok()) << joints.status().message();
    const auto& program = hmsm::detail::step_program_of(**joints);
    ASSERT_EQ(program.size(), 2u);
    EXPECT_EQ(program[0].pass, Pass::wind_force);
    EXPECT_EQ(program[1].pass, Pass::compose);
    config.outputs = Outputs::all;
    auto all = Simulation::create(scene, config);
    ASSERT_TRUE(all.ok());
    const auto& data = hmsm::detail::scene_data_of(**all);
    const auto rest = hmsm::detail::build_program(data, data.groups, Composition::path_walk, false, Pass::integrate,
                                                  (1u << kPassCount) - 1);
    ASSERT_EQ(rest.size(), 4u);  // integrate alone, the walk, node_relative with node_world, contour
    EXPECT_EQ(rest[0].pass, Pass::integrate);
    EXPECT_FALSE(hmsm::detail::runs_path_walk(rest[0]));
    EXPECT_EQ(rest[1].pass, Pass::compose);
    EXPECT_TRUE(hmsm::detail::runs_path_walk(rest[1]));
    EXPECT_EQ(rest[2].pass, Pass::node_relative);
    EXPECT_TRUE(hmsm::detail::runs_path_walk(rest[2]));
    // Without the walk after it the wind pair runs apart: its pair stores neither g nor T,
    // which level by level's integrate and compose would read.
    const uint32_t wind_only = (1u << uint32_t(Pass::wind_force)) | (1u << uint32_t(Pass::integrate)) |
                               (1u << uint32_t(Pass::compose));
    const auto apart = hmsm::detail::build_program(data, data.groups, Composition::path_walk, false,
                                                   Pass::wind_force, wind_only);
    ASSERT_GE(apart.size(), 3u);
    EXPECT_EQ(apart[0].pass, Pass::wind_force);
    EXPECT_FALSE(hmsm::detail::runs_path_walk(apart[0]));
    EXPECT_EQ(apart[1].pass, Pass::integrate);
    for (const auto& d : apart) EXPECT_FALSE(hmsm::detail::runs_path_walk(d)) << pass_name(d.pass);
}

// The walk that integrates ahead (gpu_layout.h HMSM_DISPATCH_WALK_AHEAD): where a backend asks for it, a
// step of a forest whose every instance is active runs the wind pair, the top poses (the chains
// of depth 0 to walk_top_depth of each instance) and the walk ahead; a single tree, a forest with a paused
// instance and programs without the wind pair keep the plain walk.
TEST(StepProgram, WalkAheadOnlyForStepsOfForestsWithEveryInstanceActive) {
    auto count = [](const std::vector<detail::Dispatch>& program, bool (*is)(const detail::Dispatch&)) {
        return std::count_if(program.begin(), program.end(), is);
    };
    const uint32_t all = (1u << kPassCount) - 1;
    auto forest = cpu_simulation(*grid_scene(test::small_tree(), 7, 6.0, 42), Composition::path_walk);
    ASSERT_TRUE(forest);
    const auto& data = hmsm::detail::scene_data_of(*forest);
    const auto& tree = forest->hierarchy(0);
    const uint32_t top_depth = detail::walk_top_depth(data.models[0].level_begin);
    ASSERT_GE(top_depth, 1u);
    uint32_t top = 0;
    for (const Chain& chain : tree.chains) top += chain.depth <= int32_t(top_depth) ? 1 : 0;
    ASSERT_GT(top, 1u);
    ASSERT_LT(top, tree.chains.size());
    const auto ahead = detail::build_program(data, data.groups, Composition::path_walk, false, Pass::wind_force, all, true);
    ASSERT_GE(ahead.size(), 3u);
    EXPECT_EQ(ahead[0].pass, Pass::wind_force);
    ASSERT_TRUE(detail::is_top_poses_walk(ahead[1]));
    EXPECT_EQ(ahead[1].constants.level_count, top);
    EXPECT_EQ(ahead[1].constants.element_count, 7 * top);
    EXPECT_TRUE(detail::reads_wind_slot(ahead[1]));
    EXPECT_TRUE(detail::reads_wind_slot(ahead[2]));  // the atmospheric wind of the slot after
    ASSERT_TRUE(detail::is_walk_ahead(ahead[2]));
    EXPECT_EQ(ahead[2].constants.element_count, 7 * tree.chains.size());
    EXPECT_EQ(count(ahead, detail::is_walk_ahead), 1);
    // The walk ahead writes the angles, so nothing that reads them may run beside it.
    EXPECT_TRUE(detail::dispatch_writes(ahead[2]) & detail::buffer_bit(detail::BufferId::chain_state));
    EXPECT_TRUE(detail::dispatch_reads(ahead[2]) & detail::dispatch_writes(ahead[1]));
    // Not asked for, not a step, one tree, a paused instance: the plain walk.
    const auto plain = detail::build_program(data, data.groups, Composition::path_walk, false, Pass::wind_force, all);
    EXPECT_EQ(count(plain, detail::is_walk_ahead) + count(plain, detail::is_top_poses_walk), 0);
    const auto rest = detail::build_program(data, data.groups, Composition::path_walk, false, Pass::integrate, all, true);
    EXPECT_EQ(count(rest, detail::is_walk_ahead), 0);
    auto one = cpu_simulation(*grid_scene(test::small_tree(), 1, 6.0, 42), Composition::path_walk);
    ASSERT_TRUE(one);
    const auto& one_data = hmsm::detail::scene_data_of(*one);
    EXPECT_EQ(count(detail::build_program(one_data, one_data.groups, Composition::path_walk, false, Pass::wind_force,
                                          all, true),
                    detail::is_walk_ahead),
              0);
    // A paused instance inside the group (live_control.cpp active_groups), or left out of it.
    auto groups = data.groups;
    ASSERT_EQ(groups.size(), 1u);
    groups[0].covers_paused = true;
    EXPECT_EQ(count(detail::build_program(data, groups, Composition::path_walk, false, Pass::wind_force, all, true),
                    detail::is_walk_ahead),
              0);
    groups[0].covers_paused = false;
    groups[0].instance_count -= 1;
    EXPECT_EQ(count(detail::build_program(data, groups, Composition::path_walk, false, Pass::wind_force, all, true),
                    detail::is_walk_ahead),
              0);
}

// The top poses of the walk ahead go deeper where the levels below them hold many more chains
// than the next level would add walking from the trunk: the paper-1 tree's levels (1, 12, 113,
// 760, 1,459 chains) get depth 2, the same tree split into links under the coupled dynamics
// (depth 10) depth 4; never below 1 but for a lone trunk, never the deepest level.
TEST(StepProgram, WalkTopDepthCoversTheThinTopLevels) {
    auto top_depth = [](std::vector<uint32_t> level_begin) { return detail::walk_top_depth(level_begin); };
    EXPECT_EQ(top_depth({0, 1}), 0u);
    EXPECT_EQ(top_depth({0, 1, 7}), 1u);
    EXPECT_EQ(top_depth({0, 1, 13, 126, 886, 2345}), 2u);
    EXPECT_EQ(top_depth({0, 1, 2, 5, 22, 117, 383, 922, 1612, 2156, 2356, 2362}), 4u);
    EXPECT_EQ(top_depth({0, 1, 12, 1000, 1500}), 1u);  // a bushy level 2: walking it from the trunk costs more
    EXPECT_EQ(top_depth({0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10}), 3u);  // a rod of 10 links: 7 > 2, 6 > 4, not 5 > 6
}

// Every dispatch of every composition carries a kind that fits its pass (pass_table.h
// HMSM_DISPATCH_KINDS), and `round` only where the kind is a pointer-jumping one.
TEST(StepProgram, EveryDispatchKindFitsItsPassAndOnlyJumpsUseTheRound) {
    const Scene forest = *grid_scene(test::deep_tree(5), 7, 6.0, 42);
    for (test::TestComposition composition : test::kEveryComposition) {
        auto sim = cpu_simulation(forest, composition);
        ASSERT_TRUE(sim);
        const auto& data = hmsm::detail::scene_data_of(*sim);
        for (bool walk_ahead : {false, true}) {
            for (const auto& d : detail::build_program(data, data.groups, composition.composition, false,
                                                       Pass::wind_force, (1u << kPassCount) - 1, walk_ahead,
                                                       composition.jumping_form)) {
                SCOPED_TRACE(test::name_of(composition) + " " + std::string(pass_name(d.pass)));
                ASSERT_TRUE(detail::kind_fits_pass(d.constants.kind, d.pass))
                    << "kind " << d.constants.kind;
                const bool jumps = d.constants.kind == HMSM_DISPATCH_JUMP_ROUND ||
                                   d.constants.kind == HMSM_DISPATCH_JUMP_ROUNDS_IN_DISPATCH;
                if (!jumps) EXPECT_EQ(d.constants.round, 0u);
            }
        }
    }
    EXPECT_FALSE(detail::kind_fits_pass(HMSM_DISPATCH_KIND_COUNT, Pass::compose));
    EXPECT_FALSE(detail::kind_fits_pass(HMSM_DISPATCH_WIND_PAIR, Pass::compose));
}

// The step layer's schedule of the walk that integrates ahead (AheadSchedule): a run's first step
// takes the angles the last run integrated ahead unless a live change came in between, later
// steps take the step before's; after two runs in a row each preceded by a change, a run's first
// step walks plain (and the second runs whole), every eighth such run trying the walk ahead.
TEST(StepProgram, AheadScheduleTakesWhereNothingChangedAndWalksPlainUnderSteadyChanges) {
    using detail::AheadStep;
    using Steps = std::vector<AheadStep>;
    detail::AheadSchedule schedule;
    Steps steps;
    // The plan of a run of `count` steps, as AheadSteps.
    auto plan = [&](uint32_t count, Steps& out) {
        std::vector<detail::RunStep> run(count);
        schedule.plan(run);
        out.clear();
        for (const detail::RunStep& step : run) out.push_back(step.ahead);
    };
    plan(3, steps);  // the first run: nothing integrated ahead yet
    EXPECT_EQ(steps, (Steps{AheadStep::whole, AheadStep::take, AheadStep::take}));
    plan(1, steps);  // nothing changed since
    EXPECT_EQ(steps, Steps{AheadStep::take});
    schedule.live_change();
    plan(1, steps);  // the first run after a change
    EXPECT_EQ(steps, Steps{AheadStep::whole});
    for (uint32_t streak = 2; streak <= 9; ++streak) {
        SCOPED_TRACE(streak);
        schedule.live_change();
        plan(2, steps);
        if (streak == detail::AheadSchedule::kRetryWalkAhead) EXPECT_EQ(steps, (Steps{AheadStep::whole, AheadStep::take}));
        else EXPECT_EQ(steps, (Steps{AheadStep::plain, AheadStep::whole}));
    }
    plan(1, steps);  // calm again: the last run's second step integrated ahead
    EXPECT_EQ(steps, Steps{AheadStep::take});
    schedule.forget();  // a failed run
    plan(1, steps);
    EXPECT_EQ(steps, Steps{AheadStep::whole});
    schedule.live_change();
    plan(1, steps);  // one change after a calm run: no streak
    EXPECT_EQ(steps, Steps{AheadStep::whole});
}

TEST(StepProgram, ModelsBeyondTheRoundsLimitFallBackToOneDispatchPerRound) {
    // 16,385 chains: more than 16 per thread of the largest workgroup.
    auto sim = cpu_simulation(single_tree_scene(test::broom(16385)), test::kJumpingInDispatch);
    ASSERT_TRUE(sim);
    ASSERT_EQ(sim->hierarchy(0).chains.size(), 16385u);
    for (Pass pass : {Pass::compose, Pass::root_positions}) {
        auto d = dispatches_of(*sim, pass);
        ASSERT_EQ(d.size(), sim->jump_rounds());
        for (const auto& dispatch : d) EXPECT_EQ(dispatch.constants.kind, HMSM_DISPATCH_JUMP_ROUND);
    }
    // And just under the limit the rounds stay in one dispatch.
    auto under = cpu_simulation(single_tree_scene(test::broom(16384)), test::kJumpingInDispatch);
    ASSERT_TRUE(under);
    ASSERT_EQ(under->hierarchy(0).chains.size(), 16384u);
    EXPECT_EQ(dispatches_of(*under, Pass::compose)[0].constants.kind, HMSM_DISPATCH_JUMP_ROUNDS_IN_DISPATCH);
}

TEST(StepProgram, RoundsWorkgroupSizeIsThePowerOfTwoThatCoversTheChains) {
    EXPECT_EQ(gpu::rounds_workgroup_size(1), 64u);
    EXPECT_EQ(gpu::rounds_workgroup_size(64), 64u);
    EXPECT_EQ(gpu::rounds_workgroup_size(65), 128u);
    EXPECT_EQ(gpu::rounds_workgroup_size(393), 512u);
    EXPECT_EQ(gpu::rounds_workgroup_size(1024), 1024u);
    EXPECT_EQ(gpu::rounds_workgroup_size(2345), 1024u);  // larger models loop
    EXPECT_EQ(gpu::rounds_workgroup_size(1u << 30), 1024u);
}

TEST(StepProgram, CompositionNamesRoundTrip) {
    for (Composition c : {Composition::pointer_jumping, Composition::level_by_level, Composition::path_walk,
                          Composition::automatic})
        EXPECT_EQ(parse_composition(to_string(c)), c);
    // Pointer jumping chooses its dispatch form by size; the forms have no public names.
    EXPECT_FALSE(parse_composition("pointer_jumping_per_round").has_value());
    EXPECT_FALSE(parse_composition("pointer_jumping_in_dispatch").has_value());
    EXPECT_FALSE(parse_composition("pointer-jumping").has_value());  // the CLI maps '-' to '_'
    EXPECT_FALSE(parse_composition("fused").has_value());
}

// The default composition resolves by backend: pointer jumping on the CPU backends and on
// Vulkan over a CPU driver (measured faster there), path walk on a GPU; config() says which.
TEST(StepProgram, AutomaticCompositionResolvesByBackend) {
    EXPECT_EQ(SimulationConfig{}.composition, Composition::automatic);
    const Scene scene = single_tree_scene(test::deep_tree(4));
    for (BackendKind kind : {BackendKind::cpu, BackendKind::cpu64, BackendKind::cpu_parallel, BackendKind::vulkan,
                             BackendKind::cuda}) {
        SimulationConfig config;
        config.backend = kind;
        auto sim = Simulation::create(scene, config);
        if (!sim.ok() && sim.status().code() == ErrorCode::no_device) continue;  // no such device here
        ASSERT_TRUE(sim.ok()) << to_string(kind) << ": " << sim.status().message();
        const bool gpu = kind == BackendKind::cuda ||
                         (kind == BackendKind::vulkan && !hmsm::detail::backend_of(**sim).device_name().starts_with("llvmpipe"));
        EXPECT_EQ((*sim)->config().composition, gpu ? Composition::path_walk : Composition::pointer_jumping)
            << to_string(kind) << " on " << (*sim)->device_name();
        const auto& program = hmsm::detail::step_program_of(**sim);
        bool walks = false;
        for (const auto& d : program) walks = walks || hmsm::detail::runs_path_walk(d);
        EXPECT_EQ(walks, gpu) << to_string(kind);
        if (gpu) EXPECT_EQ(program.size(), 4u);
    }
#ifdef HMSM_HAVE_CUDA
    // Without a GPU too: the CUDA kernels on the host, behind the same interface, resolve to the
    // path walk (CI has no GPU, so this is where a resolution stuck at pointer jumping shows).
    auto emulated =
        hmsm::detail::SimulationAccess::create(scene, SimulationConfig{}, test::create_cuda_emulation_backend());
    ASSERT_TRUE(emulated.ok()) << emulated.status().message();
    EXPECT_EQ((*emulated)->config().composition, Composition::path_walk);
    EXPECT_EQ(hmsm::detail::step_program_of(**emulated).size(), 4u);
#endif
}
