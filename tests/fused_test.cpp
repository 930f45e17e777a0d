// Composition::fused (passes 1-5 in one dispatch, a workgroup per instance): the step program
// it builds, and every backend against the cpu64 oracle after many steps, with the rounds in
// workgroup shared memory and in device memory (HMSM_FUSED_SHARED_BYTES=0), on models whose
// chain counts are not multiples of the workgroup size, a forest of several models, force
// fields, and instances removed and added. A backend without a device skips with the reason
// (CUDA on a machine without a GPU: the kernel bodies then run in the emulation suites).
#include "simulation_access.h"
#include "test_trees.h"

#include "backend.h"
#include "step_program.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <optional>
#include <string>

using namespace hmsm;
using detail::Dispatch;

namespace {

std::vector<double> read_output(const Simulation& sim, Output output) {
    std::vector<double> values;
    const Status s = sim.read(output, values);
    EXPECT_TRUE(s.ok()) << s.message();
    return values;
}

SimulationConfig windy(Composition composition) {
    SimulationConfig config;
    config.composition = composition;
    config.wind.profile = WindProfile::turbulent;
    config.wind.strength = 8.0;
    config.wind.direction = {1, 0, 0.3};
    config.parameters.wind_gain = 15.0;  // large angles, the clamp reached at times
    return config;
}

double scene_height(const Scene& scene) {
    double h = 0.0;
    for (const TreeModel& m : scene.models) h = std::max(h, tree_height(m));
    return h;
}

/// HMSM_FUSED_SHARED_BYTES for the lifetime of the object (backends read it when created).
class SharedBytes {
public:
    explicit SharedBytes(const char* value) {
        if (const char* old = std::getenv(kName)) old_ = old;
        if (value) setenv(kName, value, 1);
        else unsetenv(kName);
    }
    ~SharedBytes() {
        if (old_) setenv(kName, old_->c_str(), 1);
        else unsetenv(kName);
    }

private:
    static constexpr const char* kName = "HMSM_FUSED_SHARED_BYTES";
    std::optional<std::string> old_;
};

struct FusedScene {
    std::string name;
    Scene scene;
};

/// 300 chains (a workgroup of 512, 21.6 KB of rounds: shared memory even on lavapipe's 32 KB),
/// 1,100 chains (more than one workgroup of 1,024 covers: threads loop), a deep tree (three
/// rounds), and a forest of two models in four groups.
std::vector<FusedScene> fused_scenes() {
    std::vector<FusedScene> scenes;
    scenes.push_back({"broom_300", single_tree_scene(test::broom(300), {1, 0, 2}, 0.4)});
    scenes.push_back({"broom_1100", single_tree_scene(test::broom(1100))});
    scenes.push_back({"deep_tree_6", single_tree_scene(test::deep_tree(6), {3, 1, -2}, 1.1)});
    Scene forest = *grid_scene(test::small_tree(), 5, 6.0, 42);
    forest.models.push_back(test::deep_tree(4));
    forest.model_names.push_back("deep");
    forest.instances.insert(forest.instances.begin() + 2, Instance{1, {-6, 0, 8}, 0.4});
    forest.instances.push_back({1, {9, 0, -3}, 1.9, 0.7, 0.3});
    scenes.push_back({"forest_two_models", forest});
    return scenes;
}

/// Steps `sim` and the cpu64 oracle (pointer jumping) alike and compares every output: node and
/// vertex positions and joint translations within docs/model.md 7's 1e-4 of the tree height,
/// normals and rotations within 1e-3.
void expect_agrees_with_cpu64(Simulation& sim, const Scene& scene, const SimulationConfig& config,
                              uint32_t steps) {
    std::string skip;
    SimulationConfig oracle_config = config;
    oracle_config.composition = Composition::pointer_jumping;
    auto oracle = test::create_simulation_or_skip(scene, oracle_config, BackendKind::cpu64, skip);
    ASSERT_TRUE(oracle);
    ASSERT_TRUE(sim.step(steps / 2).ok());
    ASSERT_TRUE(sim.step(steps - steps / 2).ok());
    ASSERT_TRUE(oracle->step(steps).ok());
    const double height = scene_height(scene);
    for (Output o : {Output::node_positions, Output::vertex_positions, Output::chain_origins}) {
        const auto a = read_output(sim, o), b = read_output(*oracle, o);
        ASSERT_EQ(a.size(), b.size());
        EXPECT_LE(test::max_abs_difference(a, b) / height, 1e-4) << "output " << int(o);
    }
    for (Output o : {Output::vertex_normals, Output::chain_rotations, Output::joint_matrices}) {
        const auto a = read_output(sim, o), b = read_output(*oracle, o);
        ASSERT_EQ(a.size(), b.size());
        const double scale = o == Output::joint_matrices ? height : 1.0;
        EXPECT_LE(test::max_abs_difference(a, b) / scale, 1e-3) << "output " << int(o);
    }
    // The scene really moved.
    auto rest = test::create_simulation_or_skip(scene, oracle_config, BackendKind::cpu64, skip);
    EXPECT_GT(test::max_abs_difference(read_output(*rest, Output::node_positions),
                                       read_output(*oracle, Output::node_positions)),
              1e-3 * height);
}

TEST(FusedProgram, OneDispatchPerGroupReplacesPassesOneToFive) {
    Scene forest = fused_scenes().back().scene;
    auto sim = Simulation::create(forest, [] {
        SimulationConfig c = windy(Composition::fused);
        c.backend = BackendKind::cpu;
        return c;
    }());
    ASSERT_TRUE(sim.ok()) << sim.status().message();
    const auto& program = detail::step_program_of(**sim);
    const auto& data = detail::scene_data_of(**sim);
    size_t fused = 0;
    for (const Dispatch& d : program) {
        if (detail::runs_fused(d)) {
            ++fused;
            EXPECT_EQ(d.constants.round, data.jump_rounds);
            EXPECT_EQ(d.constants.src_half, HMSM_FINAL_HALF(data.jump_rounds));
            EXPECT_EQ(d.constants.element_count % d.constants.model_chain_count, 0u);
            EXPECT_EQ(detail::launch_shape(d).workgroups, d.constants.element_count / d.constants.model_chain_count);
            continue;
        }
        EXPECT_FALSE(detail::is_fused(d.pass)) << pass_name(d.pass);
    }
    EXPECT_EQ(fused, data.groups.size());
    // The fused passes first, then node_world and contour for every group.
    ASSERT_EQ(program.size(), 3 * data.groups.size());
    EXPECT_EQ(program[fused].pass, Pass::node_world);
    EXPECT_EQ(program.back().pass, Pass::contour);
}

TEST(FusedProgram, AccessIsTheUnionOfTheFusedPasses) {
    uint32_t reads = 0, writes = 0, passes = 0;
    for (Pass p : {Pass::wind_force, Pass::integrate, Pass::compose, Pass::node_relative, Pass::root_positions}) {
        reads |= detail::pass_reads(p);
        writes |= detail::pass_writes(p);
        passes |= 1u << uint32_t(p);
    }
    Dispatch d{detail::kFusedDispatchPass, {}};
    d.constants.mode = HMSM_MODE_FUSED;
    EXPECT_EQ(detail::dispatch_reads(d), reads);
    EXPECT_EQ(detail::dispatch_writes(d), writes);
    EXPECT_EQ(detail::fused_passes(), passes);
}

// Programs of some passes (the rest pose from integrate on, outputs recomputed after a removal)
// run the passes one by one, the rounds in one dispatch; joints-only steps are the fused
// dispatches alone.
TEST(FusedProgram, PartialProgramsRunThePassesOneByOne) {
    SimulationConfig config = windy(Composition::fused);
    config.backend = BackendKind::cpu;
    config.outputs = Outputs::joints;
    auto sim = Simulation::create(single_tree_scene(test::deep_tree(3)), config);
    ASSERT_TRUE(sim.ok()) << sim.status().message();
    const auto& program = detail::step_program_of(**sim);
    ASSERT_EQ(program.size(), 1u);
    EXPECT_TRUE(detail::runs_fused(program[0]));
    const auto& data = detail::scene_data_of(**sim);
    const auto rest = detail::build_program(data, data.groups, Composition::fused, false, Pass::integrate, ~0u);
    ASSERT_EQ(rest.size(), 4u);
    for (const Dispatch& d : rest) {
        EXPECT_FALSE(detail::runs_fused(d));
        if (detail::is_hierarchical(d.pass)) EXPECT_EQ(d.constants.mode, HMSM_MODE_POINTER_JUMPING_IN_DISPATCH);
    }
}

struct FusedCase {
    BackendKind backend;
    bool shared;  ///< rounds in shared memory where they fit (else HMSM_FUSED_SHARED_BYTES=0)
};

void PrintTo(const FusedCase& c, std::ostream* os) {
    *os << to_string(c.backend) << (c.shared ? " shared" : " device memory");
}

class FusedAgreement : public ::testing::TestWithParam<FusedCase> {};

TEST_P(FusedAgreement, AgreesWithCpu64After600Steps) {
    const SharedBytes bytes(GetParam().shared ? nullptr : "0");
    for (const FusedScene& s : fused_scenes()) {
        SCOPED_TRACE(s.name);
        std::string skip;
        const SimulationConfig config = windy(Composition::fused);
        auto sim = test::create_simulation_or_skip(s.scene, config, GetParam().backend, skip);
        if (!skip.empty()) GTEST_SKIP() << skip;
        ASSERT_TRUE(sim);
        expect_agrees_with_cpu64(*sim, s.scene, config, 600);
    }
}

// Force fields act at the chain origins of the previous step, which the fused dispatch reads
// before it overwrites them.
TEST_P(FusedAgreement, ForceFieldsAgreeWithCpu64) {
    const SharedBytes bytes(GetParam().shared ? nullptr : "0");
    const Scene scene = fused_scenes().back().scene;
    std::string skip;
    const SimulationConfig config = windy(Composition::fused);
    auto sim = test::create_simulation_or_skip(scene, config, GetParam().backend, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(sim);
    ForceField fields[2];
    fields[0].center = {0, 3, 0};
    fields[0].radius = 20.0;
    fields[0].directional = {0, 0, 6};
    fields[1].kind = ForceField::Kind::radial;
    fields[1].center = {5, 2, 5};
    fields[1].radius = 15.0;
    fields[1].radial = 8.0;
    ASSERT_TRUE(sim->set_force_fields(fields).ok());
    auto oracle = test::create_simulation_or_skip(scene, config, BackendKind::cpu64, skip);
    ASSERT_TRUE(oracle);
    ASSERT_TRUE(oracle->set_force_fields(fields).ok());
    ASSERT_TRUE(sim->step(200).ok());
    ASSERT_TRUE(oracle->step(200).ok());
    EXPECT_LE(test::max_abs_difference(read_output(*sim, Output::node_positions),
                                       read_output(*oracle, Output::node_positions)) /
                  scene_height(scene),
              1e-4);
}

// Instances removed and added in place (and past the capacity) with the fused program: the
// ping-pong stride is the chain capacity, instances past the live ones are never touched.
TEST_P(FusedAgreement, RemovedAndAddedInstancesAgreeWithCpu64) {
    const SharedBytes bytes(GetParam().shared ? nullptr : "0");
    const Scene scene = fused_scenes().back().scene;
    std::string skip;
    const SimulationConfig config = windy(Composition::fused);
    auto sim = test::create_simulation_or_skip(scene, config, GetParam().backend, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    SimulationConfig oracle_config = config;
    oracle_config.composition = Composition::pointer_jumping;
    auto oracle = test::create_simulation_or_skip(scene, oracle_config, BackendKind::cpu64, skip);
    ASSERT_TRUE(sim && oracle);
    auto change = [](Simulation& s, int round) {
        const uint64_t gone[] = {uint64_t(round), 3};
        ASSERT_TRUE(s.remove_instances(gone).ok());
        const Instance added[] = {{1, {12, 0, double(round)}, 0.2 * round}, {0, {-9, 0, 4}, 1.0, 0.5, 0.1},
                                  {0, {4, 0, -9}, 2.0}};
        ASSERT_TRUE(s.add_instances(added).ok());
        ASSERT_TRUE(s.set_instance_active(2, round % 2 == 0).ok());
    };
    const double height = scene_height(scene);
    for (int round = 0; round < 3; ++round) {
        ASSERT_TRUE(sim->step(40).ok());
        ASSERT_TRUE(oracle->step(40).ok());
        change(*sim, round);
        change(*oracle, round);
        ASSERT_TRUE(sim->step(40).ok());
        ASSERT_TRUE(oracle->step(40).ok());
        for (Output o : {Output::node_positions, Output::joint_matrices})
            EXPECT_LE(test::max_abs_difference(read_output(*sim, o), read_output(*oracle, o)) / height, 1e-4)
                << "output " << int(o) << " after round " << round;
    }
}

std::vector<FusedCase> fused_cases() {
    std::vector<FusedCase> cases;
    for (BackendKind kind : {BackendKind::cpu, BackendKind::cpu64, BackendKind::cpu_parallel})
        cases.push_back({kind, true});
    for (BackendKind kind : {BackendKind::vulkan, BackendKind::cuda}) {
        cases.push_back({kind, true});
        cases.push_back({kind, false});
    }
    return cases;
}

INSTANTIATE_TEST_SUITE_P(Backends, FusedAgreement, ::testing::ValuesIn(fused_cases()),
                         [](const auto& info) {
                             std::string name = to_string(info.param.backend);
                             std::replace(name.begin(), name.end(), '-', '_');
                             return name + (info.param.shared ? "_shared" : "_device_memory");
                         });

// On the CPU the fused dispatch runs the very pass functions per instance: bitwise the results
// of the rounds in one dispatch, and cpu-parallel bitwise those of cpu.
TEST(FusedCpu, BitwiseTheSeparatePassesWithRoundsInDispatch) {
    const Scene scene = fused_scenes().back().scene;
    std::vector<std::vector<double>> results;
    for (auto [kind, composition] : {std::pair{BackendKind::cpu, Composition::pointer_jumping_in_dispatch},
                                     std::pair{BackendKind::cpu, Composition::fused},
                                     std::pair{BackendKind::cpu_parallel, Composition::fused}}) {
        SimulationConfig config = windy(composition);
        config.backend = kind;
        config.cpu_threads = 3;
        auto sim = Simulation::create(scene, config);
        ASSERT_TRUE(sim.ok()) << sim.status().message();
        ASSERT_TRUE((*sim)->step(150).ok());
        results.push_back(read_output(**sim, Output::vertex_positions));
        auto joints = read_output(**sim, Output::joint_matrices);
        results.back().insert(results.back().end(), joints.begin(), joints.end());
    }
    EXPECT_EQ(results[1], results[0]);
    EXPECT_EQ(results[2], results[1]);
}

}  // namespace
