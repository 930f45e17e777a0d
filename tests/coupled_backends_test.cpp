// The coupled dynamics (docs/model.md 3.13) on every backend and composition: a forest of
// paper-5 trees (1,179 chains, no multiple of a workgroup) agrees with cpu64 over 1,000 steps of
// turbulent and atmospheric wind with live changes: a gust, a force field, an instance's wind
// scale, one instance paused and resumed, one removed and one added. The path walk runs
// wind_force and integrate in one dispatch, where a chain's load must not be overwritten before
// its parent has read it (the two halves of chain_load). The CUDA kernels also run on the host
// (cuda_emulation), so a machine without a GPU checks their arithmetic and indexing. The
// articulated exchange runs in every composition (the path walk's wind pair then runs pass 1
// only, and integrate sweeps whole instances after it).
#include "agreement/pass_agreement.h"
#include "simulation_access.h"
#include "test_trees.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace hmsm {
namespace {

struct CoupledCase {
    std::string backend;  // a name of test::backends_under_test(), or "cpu_parallel"
    WindProfile profile;
    Composition composition;
    Exchange exchange = Exchange::held;
};

Result<std::unique_ptr<detail::Backend>> backend_named(const std::string& name) {
    if (name == "cpu_parallel") return detail::create_backend(BackendKind::cpu_parallel, 3);
    for (const test::BackendUnderTest& b : test::backends_under_test())
        if (b.name == name) return b.create();
    return Status{ErrorCode::invalid_argument, "no backend named " + name};
}

/// The live changes before each of four runs of 250 steps.
void change(Simulation& sim, int phase, const Instance& added) {
    Wind gust = sim.wind();
    gust.strength *= 1.8;
    gust.direction = {0.3, 0.0, 1.0};
    ForceField push;
    push.center = {0.0, 6.0, 0.0};
    push.radius = 8.0;
    push.directional = {0.0, 0.0, 30.0};
    const uint64_t first = 0;
    if (phase == 1) ASSERT_TRUE(sim.set_wind(gust).ok());
    if (phase == 2) {
        ASSERT_TRUE(sim.set_force_fields({&push, 1}).ok());
        ASSERT_TRUE(sim.set_instance_wind_scale(1, 0.5).ok());
        ASSERT_TRUE(sim.set_instance_active(2, false).ok());
    }
    if (phase == 3) {
        ASSERT_TRUE(sim.set_force_fields({}).ok());
        ASSERT_TRUE(sim.set_instance_active(2, true).ok());
        ASSERT_TRUE(sim.remove_instances({&first, 1}).ok());
        ASSERT_TRUE(sim.add_instances({&added, 1}).ok());
    }
}

class CoupledBackends : public ::testing::TestWithParam<CoupledCase> {};

TEST_P(CoupledBackends, AgreeWithCpu64OverLiveChanges) {
    auto backend = backend_named(GetParam().backend);
    if (!backend && backend.status().code() == ErrorCode::no_device) GTEST_SKIP() << backend.status().message();
    ASSERT_TRUE(backend.ok()) << backend.status().message();
    auto preset = generate_preset("paper-5");
    ASSERT_TRUE(preset.ok());
    auto grid = grid_scene(*preset, 3, 20.0, 1);
    ASSERT_TRUE(grid.ok());
    const Scene& scene = *grid;
    SimulationConfig config;
    config.backend = BackendKind::cpu64;
    config.model.dynamics = Dynamics::coupled;
    config.model.exchange = GetParam().exchange;
    config.outputs = Outputs::joints_and_nodes;
    config.wind.profile = GetParam().profile;
    config.wind.strength = 4.0;
    config.wind.turbulence = 0.5;
    config.composition = GetParam().composition;
    auto oracle = Simulation::create(scene, config);
    ASSERT_TRUE(oracle.ok()) << oracle.status().message();
    auto tested = detail::SimulationAccess::create(scene, config, std::move(backend).value());
    ASSERT_TRUE(tested.ok()) << tested.status().message();
    Instance added = scene.instances[1];
    added.origin = {40.0, 0.0, 40.0};
    for (int phase = 0; phase < 4; ++phase) {
        for (Simulation* sim : {oracle->get(), tested->get()}) {
            change(*sim, phase, added);
            if (HasFatalFailure()) return;
            ASSERT_TRUE(sim->step(250).ok());
        }
        std::vector<double> expected, actual, angles;
        ASSERT_TRUE((*oracle)->read(Output::node_positions, expected).ok());
        ASSERT_TRUE((*tested)->read(Output::node_positions, actual).ok());
        ASSERT_TRUE((*oracle)->read(Output::chain_angles, angles).ok());
        double scale = 0.0, swing = 0.0;
        for (double v : expected) scale = std::max(scale, std::abs(v));
        for (size_t i = 0; i < angles.size(); i += 4) swing = std::max({swing, std::abs(angles[i]), std::abs(angles[i + 1])});
        ASSERT_GT(swing, 1e-3) << "the trees must sway for the comparison to mean something";
        ASSERT_TRUE(test::all_finite(actual));
        EXPECT_LT(test::max_abs_difference(actual, expected), 1e-5 * scale) << "after phase " << phase;
    }
}

constexpr WindProfile kTurbulent = WindProfile::turbulent, kAtmospheric = WindProfile::atmospheric;
constexpr Composition kWalk = Composition::path_walk, kJumping = Composition::pointer_jumping;
constexpr Composition kLevels = Composition::level_by_level;
constexpr Exchange kArticulated = Exchange::articulated;

INSTANTIATE_TEST_SUITE_P(
    Backends, CoupledBackends,
    ::testing::Values(CoupledCase{"cpu", kTurbulent, kJumping}, CoupledCase{"cpu", kAtmospheric, kWalk},
                      CoupledCase{"cpu_parallel", kTurbulent, kJumping}, CoupledCase{"cpu_parallel", kTurbulent, kWalk},
                      CoupledCase{"vulkan", kTurbulent, kWalk}, CoupledCase{"vulkan", kAtmospheric, kJumping},
                      CoupledCase{"cuda", kTurbulent, kWalk}, CoupledCase{"cuda", kAtmospheric, kWalk},
                      CoupledCase{"cuda", kAtmospheric, kJumping}, CoupledCase{"cuda_emulation", kTurbulent, kWalk},
                      CoupledCase{"cuda_emulation", kAtmospheric, kJumping},
                      // The articulated exchange (each instance swept by one work item, on the
                      // devices by one workgroup depth by depth).
                      CoupledCase{"cpu", kTurbulent, kJumping, kArticulated},
                      CoupledCase{"cpu", kAtmospheric, kLevels, kArticulated},
                      CoupledCase{"cpu_parallel", kAtmospheric, kJumping, kArticulated},
                      CoupledCase{"cpu_parallel", kTurbulent, kLevels, kArticulated},
                      CoupledCase{"cpu", kAtmospheric, kWalk, kArticulated},
                      CoupledCase{"cpu_parallel", kTurbulent, kWalk, kArticulated},
                      CoupledCase{"vulkan", kTurbulent, kJumping, kArticulated},
                      CoupledCase{"vulkan", kAtmospheric, kWalk, kArticulated},
                      CoupledCase{"cuda", kTurbulent, kJumping, kArticulated},
                      CoupledCase{"cuda", kAtmospheric, kWalk, kArticulated},
                      CoupledCase{"cuda", kTurbulent, kLevels, kArticulated},
                      CoupledCase{"cuda_emulation", kTurbulent, kJumping, kArticulated},
                      CoupledCase{"cuda_emulation", kAtmospheric, kWalk, kArticulated}),
    [](const auto& info) {
        return info.param.backend + "_" + to_string(info.param.profile) + "_" + to_string(info.param.composition) +
               (info.param.exchange == Exchange::held ? "" : "_articulated");
    });

// A forest of at least HMSM_SWEEP_WIDE_BELOW instances sweeps in workgroups of
// HMSM_WORKGROUP_SIZE, a wide depth in many turns (the nine trees above take wider workgroups):
// the chain angles agree with cpu64 too.
class ArticulatedForest : public ::testing::TestWithParam<std::string> {};

TEST_P(ArticulatedForest, NarrowSweepsAgreeWithCpu64) {
    auto backend = backend_named(GetParam());
    if (!backend && backend.status().code() == ErrorCode::no_device) GTEST_SKIP() << backend.status().message();
    ASSERT_TRUE(backend.ok()) << backend.status().message();
    auto preset = generate_preset("paper-5");
    ASSERT_TRUE(preset.ok());
    auto grid = grid_scene(*preset, HMSM_SWEEP_WIDE_BELOW + 7, 20.0, 1);
    ASSERT_TRUE(grid.ok());
    SimulationConfig config;
    config.backend = BackendKind::cpu64;
    config.model.dynamics = Dynamics::coupled;
    config.model.exchange = Exchange::articulated;
    config.outputs = Outputs::joints;
    config.wind.profile = WindProfile::turbulent;
    config.wind.strength = 4.0;
    config.wind.turbulence = 0.5;
    auto oracle = Simulation::create(*grid, config);
    ASSERT_TRUE(oracle.ok()) << oracle.status().message();
    auto tested = detail::SimulationAccess::create(*grid, config, std::move(backend).value());
    ASSERT_TRUE(tested.ok()) << tested.status().message();
    const auto& program = detail::SimulationAccess::step_program(**tested);
    const bool narrow = std::any_of(program.begin(), program.end(), [](const detail::Dispatch& d) {
        return detail::sweeps_instances(d) && detail::launch_shape(d).workgroup_size == HMSM_WORKGROUP_SIZE;
    });
    ASSERT_TRUE(narrow) << "the forest must sweep in narrow workgroups";
    ASSERT_TRUE((*oracle)->step(30).ok());
    ASSERT_TRUE((*tested)->step(30).ok());
    std::vector<double> expected, actual;
    ASSERT_TRUE((*oracle)->read(Output::chain_angles, expected).ok());
    ASSERT_TRUE((*tested)->read(Output::chain_angles, actual).ok());
    double swing = 0.0, scale = 0.0, worst = 0.0;
    for (size_t i = 0; i < expected.size(); i += 4)
        swing = std::max({swing, std::abs(expected[i]), std::abs(expected[i + 1])});
    ASSERT_GT(swing, 1e-3) << "the trees must sway for the comparison to mean something";
    ASSERT_TRUE(test::all_finite(actual));
    for (double v : expected) scale = std::max(scale, std::abs(v));  // angles and rates
    for (size_t i = 0; i < expected.size(); ++i) worst = std::max(worst, std::abs(actual[i] - expected[i]));
    EXPECT_LT(worst, 1e-4 * scale);
}

INSTANTIATE_TEST_SUITE_P(Backends, ArticulatedForest, ::testing::Values("vulkan", "cuda"),
                         [](const auto& info) { return info.param; });

}  // namespace
}  // namespace hmsm
