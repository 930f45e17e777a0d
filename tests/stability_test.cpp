// Stability: the strongest wind for a million steps stays finite with every joint
// angle within +-theta_max; parameters outside the stable range are rejected or handled by the
// inertia floor, which is counted and reported, never silently exploding.
#include "simulation_access.h"
#include "test_trees.h"

#include "backend.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <numbers>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sys/wait.h>

using namespace hmsm;

namespace {

#if defined(__SANITIZE_ADDRESS__)
constexpr bool kSanitized = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr bool kSanitized = true;
#else
constexpr bool kSanitized = false;
#endif
#else
constexpr bool kSanitized = false;
#endif
#ifdef NDEBUG
constexpr bool kOptimized = !kSanitized;
#else
constexpr bool kOptimized = false;
#endif

/// Wind strength that drives every chain of `tree` past theta_max: the static balance of a
/// chain is K theta = A s cos(theta) (see physics_test), so s = K theta_max / (A cos theta_max)
/// just reaches the bound; `factor` times that slams it.
double saturating_strength(const TreeModel& tree, const SimulationConfig& config, double factor) {
    auto h = build_hierarchy(tree, config.model, config.parameters);
    EXPECT_TRUE(h.ok()) << h.status().message();
    double s = 0.0;
    const double theta = config.parameters.max_angle;
    for (const Chain& c : h->chains)
        if (c.wind_area > 0.0) s = std::max(s, c.stiffness * theta / (c.wind_area * std::cos(theta)));
    return factor * s;
}

SimulationConfig strongest_wind(const TreeModel& tree, BackendKind backend) {
    SimulationConfig config;
    config.backend = backend;
    config.profile_passes = false;
    config.wind.profile = WindProfile::y1;  // sign changes: the chains slam from bound to bound
    config.wind.frequency = 1.0;
    config.wind.direction = {1.0, 0.0, 0.4};
    config.wind.strength = saturating_strength(tree, config, 4.0);
    return config;
}

/// Sum of segment lengths from the root: no node can be farther from its origin than this.
double reach(const TreeModel& tree) {
    double total = 0.0;
    for (const TreeNode& n : tree.nodes)
        if (n.parent >= 0) total += glm::length(n.position - tree.nodes[n.parent].position);
    return total;
}

struct Bounds {
    double max_angle_seen = 0.0;
    bool saturated = false;
};

/// Angles within the bound (exactly: the clamp writes +-theta_max in the backend's precision),
/// every output finite, every node within reach of its instance origin.
void expect_bounded(const Simulation& sim, double reach_m, Bounds& bounds, const std::string& where) {
    SCOPED_TRACE(where);
    std::vector<double> angles, nodes, vertices;
    ASSERT_TRUE(sim.read(Output::chain_angles, angles).ok());
    ASSERT_TRUE(sim.read(Output::node_positions, nodes).ok());
    ASSERT_TRUE(sim.read(Output::vertex_positions, vertices).ok());
    ASSERT_TRUE(test::all_finite(angles));
    ASSERT_TRUE(test::all_finite(nodes));
    ASSERT_TRUE(test::all_finite(vertices));
    const double theta = sim.config().parameters.max_angle;
    const double bound = sim.backend_kind() == BackendKind::cpu64 ? theta : double(float(theta));
    for (size_t c = 0; c < angles.size() / 4; ++c)
        for (int j = 0; j < 2; ++j) {
            double a = std::abs(angles[4 * c + j]);
            ASSERT_LE(a, bound) << "chain " << c;
            bounds.max_angle_seen = std::max(bounds.max_angle_seen, a);
            bounds.saturated |= a == bound;
        }
    const Scene& scene = sim.scene();
    size_t element = 0;
    for (const Instance& inst : scene.instances)
        for (size_t n = 0; n < scene.models[inst.model].nodes.size(); ++n, ++element) {
            glm::dvec3 p(nodes[3 * element], nodes[3 * element + 1], nodes[3 * element + 2]);
            ASSERT_LE(glm::length(p - inst.origin), reach_m * (1.0 + 1e-5)) << "node " << n;
        }
}

void run_bounded(const TreeModel& tree, const SimulationConfig& config, uint64_t steps,
                 uint32_t check_every) {
    auto sim = Simulation::create(single_tree_scene(tree), config);
    ASSERT_TRUE(sim.ok()) << sim.status().message();
    Bounds bounds;
    const double reach_m = reach(tree);
    for (uint64_t done = 0; done < steps;) {
        uint32_t chunk = uint32_t(std::min<uint64_t>(check_every, steps - done));
        ASSERT_TRUE((*sim)->step(chunk).ok());
        done += chunk;
        expect_bounded(**sim, reach_m, bounds, "after step " + std::to_string(done));
        if (::testing::Test::HasFatalFailure()) return;
    }
    EXPECT_TRUE(bounds.saturated) << "the wind never reached theta_max (max " << bounds.max_angle_seen << ")";
}

}  // namespace

// The paper's float path and the double oracle, 1,000,000 steps each (2.3 hours of simulated
// time at dt = 1/120) of a y1 wind four times stronger than what holds every chain at
// theta_max. Unoptimized or sanitized builds run 20,000 steps: the same code paths, in the
// time budget of CI.
TEST(Stability, MillionStepsOfSaturatingWindStayFiniteAndBounded) {
    const uint64_t steps = kOptimized ? 1'000'000 : 20'000;
    const TreeModel tree = test::small_tree();
    for (BackendKind backend : {BackendKind::cpu, BackendKind::cpu64}) {
        SCOPED_TRACE(to_string(backend));
        run_bounded(tree, strongest_wind(tree, backend), steps, 5000);
    }
}

// Every preset (10 s of simulated time); unoptimized or sanitized builds take the smallest one.
TEST(Stability, PresetsUnderSaturatingWindStayFiniteAndBounded) {
    const uint64_t steps = kOptimized ? 1200 : 120;
    for (std::string_view name : preset_names()) {
        if (!kOptimized && name != preset_names().back()) continue;
        SCOPED_TRACE(std::string(name));
        auto tree = generate_preset(name);
        ASSERT_TRUE(tree.ok()) << tree.status().message();
        run_bounded(*tree, strongest_wind(*tree, BackendKind::cpu), steps, uint32_t(steps / 4));
    }
}

// The GPU backends (float, one thread per element) under the same wind, 2,400 steps (the 1M-step
// run stays on the CPU: lavapipe in CI would take hours). Skipped without a device.
class GpuStability : public ::testing::TestWithParam<BackendKind> {};

TEST_P(GpuStability, SaturatingWindStaysFiniteAndBounded) {
    const TreeModel tree = test::small_tree();
    auto probe = Simulation::create(single_tree_scene(tree), strongest_wind(tree, GetParam()));
    if (!probe.ok() && probe.status().code() == ErrorCode::no_device) GTEST_SKIP() << probe.status().message();
    ASSERT_TRUE(probe.ok()) << probe.status().message();
    run_bounded(tree, strongest_wind(tree, GetParam()), 2400, 400);
}

INSTANTIATE_TEST_SUITE_P(Backends, GpuStability, ::testing::Values(BackendKind::vulkan, BackendKind::cuda),
                         test::BackendTestName());

namespace {

/// Chains the floor must raise: those whose free inertia gives omega*dt above the limit of
/// hierarchy.cpp (0.5, and 1/(2 zeta) for heavy damping).
int32_t expected_floored(const TreeModel& tree, const Parameters& p) {
    auto h = build_hierarchy(tree, {}, p);
    int32_t count = 0;
    for (const Chain& c : h->chains) {
        double free_inertia = p.density * c.radius * c.radius * c.length * c.length * c.length;
        // docs/model.md 3.4: f_max = min(f_cap, 1 / (4 pi dt max(1, zeta))).
        double f_max = std::min(p.max_frequency, 1.0 / (4.0 * std::numbers::pi * p.dt * std::max(1.0, p.damping_ratio)));
        double frequency = std::sqrt(c.stiffness / free_inertia) / (2.0 * std::numbers::pi);
        count += frequency > f_max * (1.0 + 1e-12);
    }
    return count;
}

}  // namespace

// A sweep over dt, stiffness and damping far outside the natural range: each combination is
// either rejected as bad input or runs under the strongest wind with finite, bounded output,
// and the chains whose inertia was raised are counted.
TEST(Stability, ExtremeParametersAreRejectedOrStayFiniteWithAFlooredCount) {
    const TreeModel tree = test::small_tree();
    int ran = 0, floored_runs = 0;
    for (double dt : {1e-7, 1.0 / 120.0, 0.1, 5.0})
        for (double stiffness : {1e-6, 1e7, 1e16})
            for (double zeta : {0.0, 0.1, 3.0, 1e4}) {
                SimulationConfig config;
                config.backend = BackendKind::cpu;
                config.parameters.dt = dt;
                config.parameters.stiffness = stiffness;
                config.parameters.damping_ratio = zeta;
                config = [&] {
                    SimulationConfig c = strongest_wind(tree, BackendKind::cpu);
                    c.parameters = config.parameters;
                    c.wind.strength = saturating_strength(tree, c, 4.0);
                    return c;
                }();
                SCOPED_TRACE("dt " + std::to_string(dt) + " stiffness " + std::to_string(stiffness) +
                             " zeta " + std::to_string(zeta));
                auto sim = Simulation::create(single_tree_scene(tree), config);
                if (!sim.ok()) {
                    EXPECT_TRUE(is_input_error(sim.status().code())) << sim.status().message();
                    continue;
                }
                ++ran;
                EXPECT_EQ(int32_t((*sim)->capped_chain_count()), expected_floored(tree, config.parameters));
                floored_runs += (*sim)->capped_chain_count() > 0;
                Bounds bounds;
                ASSERT_TRUE((*sim)->step(300).ok());
                expect_bounded(**sim, reach(tree), bounds, "after 300 steps");
            }
    EXPECT_GT(ran, 30);
    EXPECT_GT(floored_runs, 10);
}

// Heavy damping with symplectic Euler: V += dt/I (-K S - D V) is unstable once D dt / I > 2
// (and oscillates once > 1). Released from 0.1 rad without wind, a chain must only ever move
// back towards rest, whatever the damping ratio: never to the clamp, never growing.
TEST(Stability, HeavyDampingDecaysInsteadOfChattering) {
    const TreeModel tree = test::small_tree();
    for (BackendKind backend : {BackendKind::cpu, BackendKind::cpu64})
        for (double zeta : {0.5, 2.0, 10.0, 1e3, 1e6})
            for (double stiffness : {1e7, 1e12}) {
                SCOPED_TRACE(std::string(to_string(backend)) + " zeta " + std::to_string(zeta) +
                             " stiffness " + std::to_string(stiffness));
                SimulationConfig config;
                config.backend = backend;
                config.wind.profile = WindProfile::none;
                config.parameters.damping_ratio = zeta;
                config.parameters.stiffness = stiffness;
                auto sim = Simulation::create(single_tree_scene(tree), config);
                ASSERT_TRUE(sim.ok()) << sim.status().message();
                const uint64_t chains = (*sim)->chain_count();
                std::vector<double> state(4 * chains);
                for (uint64_t c = 0; c < chains; ++c) {
                    state[4 * c + 0] = 0.1;
                    state[4 * c + 1] = -0.1;
                }
                ASSERT_TRUE(hmsm::detail::backend_of(**sim).write(detail::BufferId::chain_state, 0, chains, state.data(),
                                                    detail::Scalar::f64).ok());
                double worst = 0.0;
                for (int k = 0; k < (kOptimized ? 40 : 8); ++k) {
                    ASSERT_TRUE((*sim)->step(50).ok());
                    std::vector<double> angles;
                    ASSERT_TRUE((*sim)->read(Output::chain_angles, angles).ok());
                    ASSERT_TRUE(test::all_finite(angles));
                    for (uint64_t c = 0; c < chains; ++c)
                        worst = std::max({worst, std::abs(angles[4 * c]), std::abs(angles[4 * c + 1])});
                }
                EXPECT_LE(worst, 0.1 * (1.0 + 1e-6)) << "a released chain swung wider than it started";
            }
}

// Numbers that pass every per-field check but overflow the float path when combined: a
// vanishing radius (inertia below float range), an enormous tree (inertia above it), a wind
// frequency whose phase f*t overflows, a front so slow its phase is infinite. Each is rejected
// as bad input or runs finite; none produces NaN.
TEST(Stability, RangeEdgesAreRejectedOrStayFinite) {
    struct Case {
        std::string name;
        TreeModel tree;
        SimulationConfig config;
        glm::dvec3 origin{0.0};
    };
    std::vector<Case> cases;
    auto base = [] {
        SimulationConfig c;
        c.backend = BackendKind::cpu;
        c.wind.profile = WindProfile::none;
        return c;
    };
    cases.push_back({"radius 1e-25", test::make_tree({{-1, 0, 0, 0, 1e-25}, {0, 0, 1, 0, 1e-25}}), base()});
    cases.push_back({"radius 1e-160", test::make_tree({{-1, 0, 0, 0, 1e-160}, {0, 0, 1, 0, 1e-160}}), base()});
    cases.push_back({"tree 1e120 m", test::make_tree({{-1, 0, 0, 0, 1e119}, {0, 0, 1e120, 0, 1e119}}), base()});
    Case huge_density{"density 1e300", test::small_tree(), base()};
    huge_density.config.parameters.density = 1e300;
    cases.push_back(huge_density);
    Case tiny_density{"density 1e-300", test::small_tree(), base()};
    tiny_density.config.parameters.density = 1e-300;
    cases.push_back(tiny_density);
    Case strong{"wind strength 1e300", test::small_tree(), base()};
    strong.config.wind.profile = WindProfile::y1;
    strong.config.wind.strength = 1e300;
    cases.push_back(strong);
    Case fast{"wind frequency 1e308", test::small_tree(), base()};
    fast.config.wind.profile = WindProfile::y2;
    fast.config.wind.frequency = 1e308;
    cases.push_back(fast);
    Case slow_front{"front speed 1e-320", test::small_tree(), base(), {5.0, 0.0, 0.0}};
    slow_front.config.wind.profile = WindProfile::y2;
    slow_front.config.wind.front_speed = 1e-320;
    cases.push_back(slow_front);
    Case huge_dt{"dt 1e300", test::small_tree(), base()};
    huge_dt.config.parameters.dt = 1e300;
    huge_dt.config.wind.profile = WindProfile::y1;
    cases.push_back(huge_dt);

    for (Case& c : cases) {
        for (BackendKind backend : {BackendKind::cpu, BackendKind::cpu64}) {
            SCOPED_TRACE(c.name + " on " + to_string(backend));
            c.config.backend = backend;
            auto sim = Simulation::create(single_tree_scene(c.tree, c.origin), c.config);
            if (!sim.ok()) {
                EXPECT_TRUE(is_input_error(sim.status().code())) << sim.status().message();
                EXPECT_EQ(sim.status().message().find('\n'), std::string::npos);
                continue;
            }
            Status stepped = Status::success();
            for (int k = 0; k < 6 && stepped.ok(); ++k) stepped = (*sim)->step(100);
            if (!stepped.ok()) {
                EXPECT_TRUE(is_input_error(stepped.code())) << stepped.message();
                continue;
            }
            std::vector<double> angles, nodes, vertices;
            ASSERT_TRUE((*sim)->read(Output::chain_angles, angles).ok());
            ASSERT_TRUE((*sim)->read(Output::node_positions, nodes).ok());
            ASSERT_TRUE((*sim)->read(Output::vertex_positions, vertices).ok());
            EXPECT_TRUE(test::all_finite(angles));
            EXPECT_TRUE(test::all_finite(nodes));
            EXPECT_TRUE(test::all_finite(vertices));
        }
    }
}

// The CLI reports the floor: --report's inertia_floored_chains is the library's count.
TEST(Stability, ReportCountsFlooredChains) {
    auto dir = std::filesystem::temp_directory_path() / ("hmsm_stability_report_" + std::to_string(getpid()));
    std::filesystem::create_directories(dir);
    const std::string tree = (dir / "tree.json").string(), report = (dir / "r.json").string();
    ASSERT_TRUE(save_tree(test::small_tree(), tree).ok());
    const std::string command = std::string(HMSM_CLI_PATH) + " simulate --tree " + tree +
                                " --backend cpu --steps 50 --dt 0.5 --damping-ratio 50 --wind-strength 100 --report " +
                                report + " 2>/dev/null";
    int status = std::system(command.c_str());
    ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << command;
    std::ifstream in(report);
    auto r = nlohmann::json::parse(in);
    Parameters p;
    p.dt = 0.5;
    p.damping_ratio = 50;
    EXPECT_EQ(r["capped_chains"].get<int32_t>(), expected_floored(test::small_tree(), p));
    EXPECT_GT(r["capped_chains"].get<int32_t>(), 0);
    std::filesystem::remove_all(dir);
}
