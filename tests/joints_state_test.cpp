// A joints-only simulation (Outputs::joints) keeps, per model and level of detail, only the
// nodes its steps read (the chains' attach nodes), and its joint matrices are those of the same
// scene run with every output, bit for bit, on every backend and composition, under both
// dynamics, through level switches, additions and removals.
#include "test_compositions.h"
#include "test_trees.h"

#include "agreement/cuda_emulation_backend.h"
#include "scene_data.h"
#include "simulation_access.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <string>
#include <tuple>

namespace hmsm {
namespace {

constexpr int32_t kBudgets[] = {6, 3, 1};

/// Small and deep trees on three coarser levels each, one of them paused unless `all_active`
/// (the walk ahead runs only where every instance is active).
Scene lod_forest(bool all_active = false) {
    Scene scene = *grid_scene(test::small_tree(), 4, 5.0, 7);
    scene.models.push_back(test::deep_tree(4));
    scene.model_names.push_back("deep");
    scene.instances.insert(scene.instances.begin() + 1, Instance{1, {-6, 0, 8}, 0.4});
    scene.instances.push_back({1, {9, 0, -3}, 1.9, 0.7, 0.3});
    scene.instances[2].active = all_active;
    scene.lod_budgets = {{std::begin(kBudgets), std::end(kBudgets)}, {std::begin(kBudgets), std::end(kBudgets)}};
    return scene;
}

/// A registered backend by name, or "cuda_emulation": the CUDA kernels run on the host
/// ("cuda_emulation_ahead": able to walk ahead as the CUDA backend, counting such steps in
/// `ahead`).
using Case = std::tuple<std::string, test::TestComposition>;

std::unique_ptr<Simulation> create(const std::string& backend, test::TestComposition composition,
                                   SimulationConfig config, std::string& skip, test::EmulatedAheadSteps& ahead) {
    config.composition = composition.composition;
    if (backend.rfind("cuda_emulation", 0) != 0) {
        for (BackendKind kind : {BackendKind::cpu64, BackendKind::cpu, BackendKind::cpu_parallel, BackendKind::vulkan,
                                 BackendKind::cuda})
            if (backend == to_string(kind))
                return test::create_simulation_or_skip(lod_forest(), config, kind, skip, composition.jumping_form);
        ADD_FAILURE() << "no backend " << backend;
        return nullptr;
    }
#ifdef HMSM_HAVE_CUDA
    const bool ahead_backend = backend == "cuda_emulation_ahead";
    auto sim = detail::SimulationAccess::create(
        lod_forest(ahead_backend), config, test::create_cuda_emulation_backend(ahead_backend ? &ahead : nullptr),
        composition.jumping_form);
    EXPECT_TRUE(sim.ok()) << sim.status().message();
    return sim ? std::move(sim).value() : nullptr;
#else
    (void)ahead;
    skip = "this build of hmsm has no CUDA kernels to emulate";
    return nullptr;
#endif
}

std::vector<float> read_floats(const Simulation& sim, Output output) {
    std::vector<float> values;
    const Status read = sim.read(output, values);
    EXPECT_TRUE(read.ok()) << read.message();
    return values;
}

/// The chains' distinct attach nodes of `h`: the nodes a joints-only step keeps.
uint64_t distinct_attach_nodes(const Hierarchy& h) {
    std::set<int32_t> nodes;
    for (const Chain& chain : h.chains) nodes.insert(chain.attach_node);
    return nodes.size();
}

/// The joints-only simulation stores the kept nodes of each instance's model and level, and
/// counts the skeleton's nodes as the one with every output does.
void expect_kept_nodes(const Simulation& joints, const Simulation& all, const std::string& when) {
    const detail::SceneData& d = detail::scene_data_of(joints);
    uint64_t kept = 0, whole = 0;
    for (const Instance& instance : joints.instances()) {
        const Hierarchy& h = joints.hierarchy(instance.model);
        EXPECT_EQ(d.models[instance.model].node_count, distinct_attach_nodes(h)) << when << ", model " << instance.model;
        EXPECT_LT(d.models[instance.model].node_count, h.node_owner.size()) << when;
        kept += distinct_attach_nodes(h);
        whole += h.node_owner.size();
    }
    EXPECT_EQ(d.total_nodes, kept) << when;
    EXPECT_EQ(d.element_count(detail::BufferId::node_relative), d.node_capacity) << when;
    EXPECT_EQ(d.element_count(detail::BufferId::node_world), 0u) << when;
    EXPECT_EQ(joints.node_count(), whole) << when;
    EXPECT_EQ(joints.node_count(), all.node_count()) << when;
    EXPECT_EQ(detail::scene_data_of(all).total_nodes, whole) << when;
}

/// Joint matrices and angles of the two simulations, bit for bit.
void expect_same_joints(const Simulation& joints, const Simulation& all, const std::string& when) {
    ASSERT_EQ(joints.chain_count(), all.chain_count()) << when;
    EXPECT_TRUE(test::same_bits(read_floats(joints, Output::joint_matrices), read_floats(all, Output::joint_matrices)))
        << when << ": joint matrices differ";
    EXPECT_TRUE(test::same_bits(read_floats(joints, Output::chain_angles), read_floats(all, Output::chain_angles)))
        << when << ": chain angles differ";
}

class JointsState : public ::testing::TestWithParam<Case> {};

TEST_P(JointsState, KeepsAttachNodesAndJointMatricesOfEveryOutput) {
    const auto& [backend, composition] = GetParam();
    test::EmulatedAheadSteps ahead;
    for (Dynamics dynamics : {Dynamics::paper, Dynamics::coupled}) {
        const std::string named = to_string(dynamics);
        SimulationConfig config = test::windy_config();
        config.model.dynamics = dynamics;
        std::string skip;
        auto all = create(backend, composition, config, skip, ahead);
        if (!skip.empty()) GTEST_SKIP() << skip;
        config.outputs = Outputs::joints;
        auto joints = create(backend, composition, config, skip, ahead);
        ASSERT_TRUE(all && joints);
        expect_kept_nodes(*joints, *all, named + " at rest");
        expect_same_joints(*joints, *all, named + " at rest");
        std::vector<float> nodes;
        EXPECT_EQ(joints->read(Output::node_positions, nodes).code(), ErrorCode::invalid_argument);

        // Steps; a switch to coarser levels (in place); steps; instances added and removed
        // (past the capacity: the state is laid out anew); a switch back to finer levels;
        // steps.
        for (Simulation* sim : {all.get(), joints.get()}) ASSERT_TRUE(sim->step(7).ok());
        expect_same_joints(*joints, *all, named + " after 7 steps");
        const InstanceId coarser[] = {InstanceId(0), InstanceId(1), InstanceId(3)};
        const uint32_t coarse_levels[] = {2, 3, 1};
        for (Simulation* sim : {all.get(), joints.get()}) {
            ASSERT_TRUE(sim->set_instance_lods(coarser, coarse_levels).ok());
            ASSERT_TRUE(sim->step(4).ok());
        }
        expect_kept_nodes(*joints, *all, named + " on coarser levels");
        expect_same_joints(*joints, *all, named + " on coarser levels");
        const Instance added[] = {{1, {2, 0, 12}, 0.9}, {0, {-3, 0, -9}, 2.2, 1.3}};
        const InstanceId removed[] = {InstanceId(4)};
        for (Simulation* sim : {all.get(), joints.get()}) {
            ASSERT_TRUE(sim->add_instances(added).ok());
            ASSERT_TRUE(sim->swap_remove_instances(removed).ok());
            ASSERT_TRUE(sim->step(3).ok());
        }
        expect_kept_nodes(*joints, *all, named + " after additions and removals");
        expect_same_joints(*joints, *all, named + " after additions and removals");
        const InstanceId finer[] = {InstanceId(1), InstanceId(3), *joints->id_of(joints->instance_count() - 1)};
        const uint32_t fine_levels[] = {0, 0, 2};
        for (Simulation* sim : {all.get(), joints.get()}) {
            ASSERT_TRUE(sim->set_instance_lods(finer, fine_levels).ok());
            ASSERT_TRUE(sim->step(5).ok());
        }
        expect_kept_nodes(*joints, *all, named + " back on finer levels");
        expect_same_joints(*joints, *all, named + " back on finer levels");
    }
    if (backend == "cuda_emulation_ahead" && composition.composition == Composition::path_walk)
        EXPECT_GT(ahead.taken, 0u) << "no step walked ahead: the case does not cover the walk ahead";
}

std::string case_name(const ::testing::TestParamInfo<Case>& info) {
    std::string name = std::get<0>(info.param) + "_" + test::name_of(std::get<1>(info.param));
    std::replace(name.begin(), name.end(), '-', '_');
    return name;
}

INSTANTIATE_TEST_SUITE_P(Backends, JointsState,
                         ::testing::Combine(::testing::Values("cpu64", "cpu", "cpu-parallel", "vulkan", "cuda",
                                                              "cuda_emulation", "cuda_emulation_ahead"),
                                            ::testing::ValuesIn(test::kEveryComposition)),
                         case_name);

}  // namespace
}  // namespace hmsm
