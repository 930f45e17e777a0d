// The pass table (src/pass_table.h): the facts every backend derives from it hold together, and
// the step program follows its domain and hierarchy columns.
#include "simulation_access.h"
#include "test_trees.h"

#include "backend.h"
#include "pass_table.h"

#include <gtest/gtest.h>

using namespace hmsm;
using namespace hmsm::detail;

namespace {

TEST(PassTable, AccessMasksAreTheTableColumns) {
    for (Pass pass : kAllPasses) {
        EXPECT_EQ(pass_reads(pass), pass_info(pass).reads) << pass_name(pass);
        EXPECT_EQ(pass_writes(pass), pass_info(pass).writes) << pass_name(pass);
        EXPECT_NE(pass_writes(pass), 0u) << pass_name(pass) << " writes nothing";
    }
}

// The hierarchical passes accumulate down the hierarchy through a ping-pong buffer: exactly they
// write a buffer of two halves, and each reads what it writes (round r reads round r-1).
TEST(PassTable, HierarchicalPassesAreThePingPongWriters) {
    for (Pass pass : kAllPasses) {
        bool writes_halves = false;
        for (uint32_t b = 0; b < kBufferCount; ++b)
            if ((pass_writes(pass) >> b & 1u) && buffer_info(BufferId(b)).scope == Scope::chain_halves)
                writes_halves = true;
        EXPECT_EQ(is_hierarchical(pass), writes_halves) << pass_name(pass);
        if (is_hierarchical(pass)) {
            EXPECT_EQ(pass_domain(pass), PassDomain::chain) << pass_name(pass);
        }
    }
}

// Every state buffer a pass reads is written by some pass (its own earlier step included), and
// no pass writes a static buffer.
TEST(PassTable, ReadsOfStateHaveAWriter) {
    uint32_t written = 0;
    for (Pass pass : kAllPasses) written |= pass_writes(pass);
    for (Pass pass : kAllPasses) {
        for (uint32_t b = 0; b < kBufferCount; ++b) {
            const BufferId id = BufferId(b);
            if ((pass_reads(pass) >> b & 1u) && is_state(id))
                EXPECT_TRUE(written >> b & 1u) << pass_name(pass) << " reads " << buffer_info(id).name;
            if (pass_writes(pass) >> b & 1u) {
                EXPECT_FALSE(is_static(id)) << pass_name(pass) << " writes " << buffer_info(id).name;
            }
        }
    }
}

// Non-hierarchical dispatches have one thread per element of their domain in every instance.
TEST(PassTable, StepProgramCountsFollowTheDomainColumn) {
    Scene scene;
    scene.models.push_back(test::small_tree());
    scene.model_names.push_back("small");
    for (int i = 0; i < 3; ++i) scene.instances.push_back(Instance{0, {double(i) * 4.0, 0.0, 0.0}});
    SimulationConfig config;
    config.backend = BackendKind::cpu;
    config.outputs = Outputs::all;
    auto sim = Simulation::create(scene, config);
    ASSERT_TRUE(sim.ok()) << sim.status().message();
    const auto program = step_program_of(*sim.value());
    uint32_t seen = 0;
    for (const Dispatch& d : program) {
        seen |= 1u << uint32_t(d.pass);
        if (is_hierarchical(d.pass)) continue;
        const auto& c = d.constants;
        const uint32_t per_domain[] = {c.model_chain_count, c.model_node_count, c.model_vertex_count};
        EXPECT_EQ(d.constants.element_count, 3u * per_domain[uint32_t(pass_domain(d.pass))])
            << pass_name(d.pass);
    }
    EXPECT_EQ(seen, (1u << kPassCount) - 1) << "every pass is dispatched with Outputs::all";
}

// Outputs on demand: a step dispatches exactly the passes whose needed_for column its outputs
// reach, and the joint matrices need no pass after root_positions.
TEST(PassTable, StepProgramFollowsTheNeededForColumn) {
    Scene scene;
    scene.models.push_back(test::small_tree());
    scene.model_names.push_back("small");
    scene.instances.push_back(Instance{0, {0.0, 0.0, 0.0}});
    for (Outputs outputs : {Outputs::joints, Outputs::joints_and_nodes, Outputs::all}) {
        SimulationConfig config;
        config.backend = BackendKind::cpu;
        config.outputs = outputs;
        auto sim = Simulation::create(scene, config);
        ASSERT_TRUE(sim.ok()) << sim.status().message();
        uint32_t seen = 0;
        for (const Dispatch& d : step_program_of(*sim.value())) seen |= 1u << uint32_t(d.pass);
        for (Pass pass : kAllPasses)
            EXPECT_EQ((seen >> uint32_t(pass)) & 1u, pass_runs_for(pass, outputs) ? 1u : 0u)
                << pass_name(pass) << " with outputs " << to_string(outputs);
    }
    for (Pass pass : kAllPasses)
        if (uint32_t(pass) <= uint32_t(Pass::root_positions))
            EXPECT_TRUE(pass_runs_for(pass, Outputs::joints)) << pass_name(pass);
    EXPECT_FALSE(pass_runs_for(Pass::node_world, Outputs::joints));
    EXPECT_TRUE(pass_runs_for(Pass::node_world, Outputs::joints_and_nodes));
    EXPECT_FALSE(pass_runs_for(Pass::contour, Outputs::joints_and_nodes));
}

}  // namespace
