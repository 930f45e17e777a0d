// The model revisions of docs/model.md 3.4 (frequency cap, wind gain) and 3.5 (turbulent
// profile, wind clock), checked against values computed independently (python3, double).
#include "test_trees.h"

#include "live_wind.h"
#include "simulation_access.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

namespace hmsm {
namespace {

using detail::BufferId;

TEST(LiveModel, Splitmix64MatchesReference) {
    EXPECT_EQ(splitmix64(0), 0xE220A8397B1DCDAFull);
    EXPECT_EQ(splitmix64(7), 0x63CBE1E459320DD7ull);
}

TEST(LiveModel, TurbulentProfileMatchesIndependentValues) {
    // python3: a_k, u_k and Yt(x) = 1 + sum a_k cos(2 pi (m_k x + u_k)) for sigma 0.3, seed 7.
    const TurbulentModes modes = turbulent_modes(0.3, 7);
    EXPECT_NEAR(modes.amplitude[0], 0.06667934111776978, 1e-15);
    EXPECT_NEAR(modes.phase[0], 0.3898297483912715, 1e-16);
    EXPECT_NEAR(modes.phase[31], 0.9179963877165437, 1e-16);
    EXPECT_DOUBLE_EQ(modes.multiple[8], 1.0);
    EXPECT_DOUBLE_EQ(modes.multiple[0], 0.25);
    Wind wind;
    wind.profile = WindProfile::turbulent;
    wind.turbulence = 0.3;
    wind.seed = 7;
    EXPECT_NEAR(wind_value(wind, 0.0), 0.672826042902195, 1e-13);
    EXPECT_NEAR(wind_value(wind, 0.37), 1.1759381188798486, 1e-13);
    EXPECT_NEAR(wind_value(wind, 1234.567), 1.0252634070331683, 1e-10);
    // The seed is an unsigned 64-bit integer: seed + k wraps mod 2^64.
    wind.turbulence = 2.0;
    wind.seed = ~uint64_t(0);
    EXPECT_NEAR(wind_value(wind, 0.25), 0.6133864255287542, 1e-13);
    // The variance of the fluctuation is sigma^2: sum a_k^2 / 2 = sigma^2.
    const TurbulentModes strong = turbulent_modes(1.5, 3);
    double variance = 0.0;
    for (double a : strong.amplitude) variance += a * a / 2.0;
    EXPECT_NEAR(variance, 1.5 * 1.5, 1e-12);
}

TEST(LiveModel, WindStrengthForSpeed) {
    EXPECT_DOUBLE_EQ(wind_strength_for_speed(6.0), 1.0);
    EXPECT_DOUBLE_EQ(wind_strength_for_speed(12.0), 4.0);
    EXPECT_DOUBLE_EQ(Parameters{}.wind_gain, 0.2);
}

TEST(LiveModel, FrequencyCapRaisesInertia) {
    // A 0.3 m twig of radius 5 mm: raw frequency 28 Hz. python3: K = 1e7 r^4 / L, I = r^2 L^3,
    // I_cap = K / (2 pi 4)^2 at dt = 1/120 (f_max = min(4, 1/(4 pi dt)) = 4 Hz).
    TreeModel twig = test::make_tree({{-1, 0, 0, 0, 0.005}, {0, 0, 0.3, 0, 0.005}});
    auto h = build_hierarchy(twig, {}, {});
    ASSERT_TRUE(h.ok());
    const Chain& c = h->chains[0];
    EXPECT_NEAR(c.stiffness, 0.020833333333333336, 1e-17);
    EXPECT_NEAR(c.inertia, 3.29821561335735e-05, 1e-18);
    EXPECT_NEAR(c.damping, 0.0001657863990540577, 1e-18);
    EXPECT_TRUE(c.capped);
    EXPECT_EQ(h->capped_chain_count, 1);
    // At dt = 1/30 and zeta = 2 the stability bound 1/(4 pi dt max(1, zeta)) = 1.19 Hz binds.
    Parameters coarse;
    coarse.dt = 1.0 / 30.0;
    coarse.damping_ratio = 2.0;
    auto hc = build_hierarchy(twig, {}, coarse);
    ASSERT_TRUE(hc.ok());
    EXPECT_NEAR(hc->chains[0].inertia, 0.0003703703703703704, 1e-17);
    // A trunk far below the cap keeps its inertia.
    auto trunk = build_hierarchy(test::rod(1, 15.0, 0.25), {}, {});
    ASSERT_TRUE(trunk.ok());
    EXPECT_FALSE(trunk->chains[0].capped);
    EXPECT_DOUBLE_EQ(trunk->chains[0].inertia, 0.25 * 0.25 * 15.0 * 15.0 * 15.0);
    Parameters bad;
    bad.max_frequency = 0.0;
    EXPECT_FALSE(validate(bad).ok());
}

TEST(LiveModel, WindRangesAreValidated) {
    auto rejected = [](auto change) {
        Wind w;
        change(w);
        return !validate(w).ok();
    };
    EXPECT_TRUE(rejected([](Wind& w) { w.turbulence = -0.1; }));
    EXPECT_TRUE(rejected([](Wind& w) { w.turbulence = 2.5; }));
    EXPECT_TRUE(rejected([](Wind& w) { w.front_speed = 0.005; }));
    EXPECT_FALSE(rejected([](Wind& w) { w.front_speed = 0.01; }));
    EXPECT_FALSE(rejected([](Wind& w) { w.turbulence = 2.0; }));
}

/// The first moment of peak deflection and the steady angle of a capped twig in a constant wind.
struct TwigResponse {
    double peak_time = 0.0, steady = 0.0;
    std::vector<double> every_60th;  ///< the angle at t = k / 60 s
};
TwigResponse twig_response(double dt) {
    TreeModel twig = test::make_tree({{-1, 0, 0, 0, 0.005}, {0, 0, 0.3, 0, 0.005}});
    SimulationConfig config;
    config.backend = BackendKind::cpu64;
    config.parameters.dt = dt;
    config.wind.profile = WindProfile::constant;
    config.wind.strength = 0.05;
    auto sim = Simulation::create(single_tree_scene(twig), config);
    EXPECT_TRUE(sim.ok());
    TwigResponse r;
    double previous = 0.0;
    std::vector<double> angles;
    const uint32_t steps = uint32_t(std::lround(4.0 / dt));
    for (uint32_t n = 1; n <= steps; ++n) {
        EXPECT_TRUE((*sim)->step().ok());
        EXPECT_TRUE((*sim)->read(Output::chain_angles, angles).ok());
        const double theta = std::hypot(angles[0], angles[1]);
        if ((n * 60) % uint32_t(std::lround(1.0 / dt)) == 0)  // t = n dt is a multiple of 1/60 s
            r.every_60th.push_back(theta);
        if (r.peak_time == 0.0 && n > 1 && theta < previous) r.peak_time = double(n - 1) * dt;
        previous = theta;
    }
    r.steady = previous;
    return r;
}

TEST(LiveModel, CappedChainsMoveIndependentlyOfDt) {
    // Raw frequency 28 Hz, capped at 4 Hz: the first peak of the step response comes half a
    // period in (0.125 s) at every dt, where the earlier dt floor rang at 0.5 / (2 pi dt).
    const TwigResponse a = twig_response(1.0 / 60.0), b = twig_response(1.0 / 120.0),
                       c = twig_response(1.0 / 240.0);
    for (const TwigResponse& r : {a, b, c}) {
        EXPECT_NEAR(r.peak_time, 0.125, 0.02);
        EXPECT_GT(r.steady, 0.0);
    }
    EXPECT_NEAR(a.steady, c.steady, 1e-3 * c.steady);
    EXPECT_NEAR(b.steady, c.steady, 1e-3 * c.steady);
    // The whole motion agrees, sampled at 60 Hz, up to symplectic Euler's own discretization
    // error (omega dt = 0.42 at 1/60 s, 0.21 at 1/120 s): the chain sways at 4 Hz at every dt,
    // where the earlier floor made it ring at 4.8, 9.5 and 19 Hz.
    ASSERT_EQ(a.every_60th.size(), c.every_60th.size());
    ASSERT_EQ(b.every_60th.size(), c.every_60th.size());
    const double peak = *std::max_element(c.every_60th.begin(), c.every_60th.end());
    double worst_a = 0.0, worst_b = 0.0;
    for (size_t k = 0; k < c.every_60th.size(); ++k) {
        worst_a = std::max(worst_a, std::abs(a.every_60th[k] - c.every_60th[k]));
        worst_b = std::max(worst_b, std::abs(b.every_60th[k] - c.every_60th[k]));
    }
    std::printf("twig at 1/60 and 1/120 vs 1/240: %.3g, %.3g of the peak\n", worst_a / peak, worst_b / peak);
    EXPECT_LE(worst_a, 0.15 * peak);
    EXPECT_LE(worst_b, 0.05 * peak);
}

/// g of every chain after one step, from the R and O before it, with the wind of docs/model.md
/// 3.5/3.9 evaluated here in double (wind_value, the clock tau passed in).
void expect_forces(Simulation& sim, double tau, std::span<const ForceField> fields) {
    const auto& data = detail::scene_data_of(sim);
    const uint32_t half = (data.jump_rounds - 1) & 1;
    std::vector<double> rot(data.total_chains * 12), org(data.total_chains * 4), force(data.total_chains * 2);
    auto& backend = detail::backend_of(sim);
    ASSERT_TRUE(backend.read(BufferId::chain_rotation, half * data.chain_capacity, data.total_chains, rot.data(),
                             detail::Scalar::f64).ok());
    ASSERT_TRUE(backend.read(BufferId::chain_origin, half * data.chain_capacity, data.total_chains, org.data(),
                             detail::Scalar::f64).ok());
    ASSERT_TRUE(sim.step().ok());
    ASSERT_TRUE(backend.read(BufferId::chain_force, 0, data.total_chains, force.data(), detail::Scalar::f64).ok());
    const Wind& wind = sim.wind();
    const glm::dvec3 d = glm::normalize(wind.direction);
    uint64_t chain = 0;
    for (const Instance& inst : sim.instances()) {
        const Hierarchy& h = sim.hierarchy(inst.model);
        const double phi = inst.wind_phase + (wind.front_speed > 0 ? -wind.frequency * glm::dot(inst.origin, d) / wind.front_speed : 0.0);
        const glm::dvec3 w_inst = inst.wind_scale * wind.strength * wind_value(wind, tau + phi) * d;
        for (const Chain& c : h.chains) {
            glm::dvec3 x(org[4 * chain], org[4 * chain + 1], org[4 * chain + 2]);
            glm::dvec3 w = w_inst;
            for (const ForceField& f : fields) {
                const double dist = glm::length(x - f.center);
                const double reach = std::max(0.0, 1.0 - dist / f.radius);
                if (f.kind == ForceField::Kind::directional) w += reach * reach * f.directional;
                else if (dist >= 1e-9) w += reach * reach * f.radial * (x - f.center) / dist;
            }
            glm::dmat3 r;
            for (int col = 0; col < 3; ++col)
                for (int row = 0; row < 3; ++row) r[col][row] = rot[12 * chain + 4 * col + row];
            const glm::dvec3 local = glm::transpose(r) * w;
            const double scale = std::max(1.0, c.wind_area * glm::length(w));
            if (!inst.active) {
                ++chain;
                continue;
            }
            EXPECT_NEAR(force[2 * chain], c.wind_area * local.z, 1e-12 * scale) << "chain " << chain;
            EXPECT_NEAR(force[2 * chain + 1], -c.wind_area * local.x, 1e-12 * scale) << "chain " << chain;
            ++chain;
        }
    }
}

TEST(LiveModel, WindClockIsContinuousAcrossChanges) {
    Scene scene = *grid_scene(test::small_tree(), 3, 4.0, 5);
    scene.instances[1].wind_phase = 0.3;
    scene.instances[2].wind_scale = 0.5;
    SimulationConfig config;
    config.backend = BackendKind::cpu64;
    config.wind.profile = WindProfile::turbulent;
    config.wind.seed = 11;
    config.wind.frequency = 0.2;
    config.wind.strength = 3.0;
    config.wind.direction = {1, 0, 0.5};
    auto sim = Simulation::create(scene, config);
    ASSERT_TRUE(sim.ok());
    const double dt = config.parameters.dt;
    ASSERT_TRUE((*sim)->step(40).ok());
    // Step 41 with the wind in force since step 1: tau = f (n - 1) dt.
    expect_forces(**sim, 0.2 * dt * 40, {});
    // From step 42 the frequency is 0.7: tau_42 = 0.2 dt 41 (continuous), then + 0.7 dt per step.
    Wind faster = (*sim)->wind();
    faster.frequency = 0.7;
    faster.front_speed = 3.0;
    ASSERT_TRUE((*sim)->set_wind(faster).ok());
    expect_forces(**sim, (0.2 * dt) * 41, {});
    ASSERT_TRUE((*sim)->step(9).ok());  // steps 43..51
    expect_forces(**sim, (0.2 * dt) * 41 + (0.7 * dt) * 10, {});  // step 52
    // A periodic profile, fields of both kinds, and a changed instance phase.
    Wind periodic = faster;
    periodic.profile = WindProfile::y2;
    ASSERT_TRUE((*sim)->set_wind(periodic).ok());
    const double tau53 = (0.2 * dt) * 41 + (0.7 * dt) * 11;
    std::vector<ForceField> fields(2);
    fields[0].center = {0, 1.5, 0};
    fields[0].radius = 3.0;
    fields[0].directional = {0, 0, 4};
    fields[1].kind = ForceField::Kind::radial;
    fields[1].center = {4, 1, 0};
    fields[1].radius = 2.5;
    fields[1].radial = -2.0;
    ASSERT_TRUE((*sim)->set_force_fields(fields).ok());
    ASSERT_TRUE((*sim)->set_instance_wind_phase(0, 1.75).ok());
    expect_forces(**sim, tau53, fields);
}

TEST(LiveModel, LongStepCallsMatchSingleSteps) {
    // step(n) runs in chunks of wind-table slots; the clock must count across them.
    SimulationConfig config;
    config.backend = BackendKind::cpu64;
    config.wind.profile = WindProfile::turbulent;
    config.wind.strength = 20.0;
    auto a = Simulation::create(single_tree_scene(test::small_tree()), config);
    auto b = Simulation::create(single_tree_scene(test::small_tree()), config);
    ASSERT_TRUE(a.ok() && b.ok());
    ASSERT_TRUE((*a)->step(700).ok());
    for (int n = 0; n < 700; ++n) ASSERT_TRUE((*b)->step().ok());
    std::vector<double> x, y;
    ASSERT_TRUE((*a)->read(Output::node_positions, x).ok());
    ASSERT_TRUE((*b)->read(Output::node_positions, y).ok());
    EXPECT_EQ(x, y);
}

TEST(LiveModel, FloatClockStaysPreciseAfterHours) {
    // Three hours in, the turbulent wind on the float CPU backend still agrees with cpu64: the
    // host reduces tau and the mode phases in double.
    SimulationConfig config;
    config.wind.profile = WindProfile::turbulent;
    config.wind.strength = 4.0;
    config.wind.frequency = 0.3;
    config.wind.front_speed = 5.0;
    Scene scene = *grid_scene(test::small_tree(), 2, 30.0, 1);
    std::vector<double> results[2];
    int k = 0;
    for (BackendKind kind : {BackendKind::cpu, BackendKind::cpu64}) {
        config.backend = kind;
        auto sim = Simulation::create(scene, config);
        ASSERT_TRUE(sim.ok());
        detail::SimulationAccess::impl(**sim).steps_done_ = uint64_t(3 * 3600) * 120;
        ASSERT_TRUE((*sim)->step(300).ok());
        ASSERT_TRUE((*sim)->read(Output::node_positions, results[k++]).ok());
    }
    EXPECT_LE(test::max_abs_difference(results[0], results[1]), 1e-4 * 4.0);
}

}  // namespace
}  // namespace hmsm
