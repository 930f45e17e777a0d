// The wind of a step (docs/model.md 3.5): the paper's dynamics samples it at the step's start;
// `coupled` at the step's midpoint, with each turbulent and atmospheric mode averaged over the
// step (its amplitude times sinc of the mode's cycles per step), so that the impulse a step
// takes is the wind's over the step to second order and modes faster than the step do not alias
// into its sway.
#include "live_wind.h"
#include "simulation_access.h"
#include "test_trees.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace hmsm {
namespace {

/// The wind table's header and the slot of the first step, after one step.
std::vector<double> first_step_table(const Wind& wind, Dynamics dynamics, double dt) {
    SimulationConfig config;
    config.backend = BackendKind::cpu64;
    config.wind = wind;
    config.parameters.dt = dt;
    config.model.dynamics = dynamics;
    auto sim = Simulation::create(single_tree_scene(test::small_tree()), config);
    EXPECT_TRUE(sim.ok()) << sim.status().message();
    std::vector<double> table(4 * size_t(HMSM_WIND_STEPS + HMSM_WIND_STEP_VEC4S));
    if (!sim.ok()) return table;
    EXPECT_TRUE((*sim)->step(1).ok());
    EXPECT_TRUE(detail::backend_of(**sim)
                    .read(detail::BufferId::wind_table, 0, HMSM_WIND_STEPS + HMSM_WIND_STEP_VEC4S, table.data(),
                          detail::Scalar::f64)
                    .ok());
    return table;
}

double mean_factor(double cycles) {
    const double x = std::numbers::pi * cycles;
    return std::sin(x) / x;
}

double frac(double x) { return x - std::floor(x); }

TEST(StepWind, PaperSamplesTheStartAndCoupledTheMeanOverTheStep) {
    Wind wind;
    wind.profile = WindProfile::turbulent;
    wind.frequency = 0.8;
    wind.strength = 2.0;
    wind.seed = 11;
    const double dt = 1.0 / 30.0;
    const TurbulentModes modes = turbulent_modes(wind.turbulence, wind.seed);
    const std::vector<double> paper = first_step_table(wind, Dynamics::paper, dt);
    const std::vector<double> coupled = first_step_table(wind, Dynamics::coupled, dt);
    const size_t slot = 4 * size_t(HMSM_WIND_STEPS);
    EXPECT_EQ(paper[slot], 0.0) << "step 1 of the paper's dynamics samples t = 0";
    const double mid = wind.frequency * dt / 2;  // the clock at the step's midpoint
    EXPECT_NEAR(coupled[slot], mid, 1e-15);
    for (uint32_t k = 0; k < kTurbulentModes; ++k) {
        const double cycles = modes.multiple[k] * wind.frequency * dt;  // the mode's cycles per step
        EXPECT_EQ(paper[4 * HMSM_WIND_AMPLITUDES + k], modes.amplitude[k]) << "mode " << k;
        EXPECT_NEAR(coupled[4 * HMSM_WIND_AMPLITUDES + k], modes.amplitude[k] * mean_factor(cycles), 1e-15)
            << "mode " << k;
        EXPECT_NEAR(paper[slot + 4 + k], frac(modes.phase[k]), 1e-12) << "mode " << k;
        EXPECT_NEAR(coupled[slot + 4 + k], frac(modes.multiple[k] * mid + modes.phase[k]), 1e-12) << "mode " << k;
    }
    // The fastest mode runs 1.4 cycles a step at this dt: averaged over the step its sign turns.
    EXPECT_LT(coupled[4 * HMSM_WIND_AMPLITUDES + kTurbulentModes - 1], 0.0);
}

TEST(StepWind, AtmosphericModesAreAveragedOverTheDistanceOfAStep) {
    Wind wind;
    wind.profile = WindProfile::atmospheric;
    wind.strength = wind_strength_for_speed(10.0);
    wind.seed = 5;
    const double dt = 1.0 / 60.0;
    const AtmosphericModes modes = atmospheric_modes(wind.turbulence, wind.seed);
    const std::vector<double> coupled = first_step_table(wind, Dynamics::coupled, dt);
    const double travel = wind_clock_rate(wind) * dt;  // metres the mean wind moves in a step
    EXPECT_NEAR(travel, 10.0 * dt, 1e-12);
    EXPECT_NEAR(coupled[4 * size_t(HMSM_WIND_STEPS)], travel / 2, 1e-14);
    for (uint32_t k = 0; k < kTurbulentModes; ++k)
        EXPECT_NEAR(coupled[4 * HMSM_WIND_AMPLITUDES + k], modes.amplitude[k] * mean_factor(modes.wavenumber[k] * travel),
                    1e-15)
            << "mode " << k;
    const std::vector<double> paper = first_step_table(wind, Dynamics::paper, dt);
    for (uint32_t k = 0; k < kTurbulentModes; ++k) EXPECT_EQ(paper[4 * HMSM_WIND_AMPLITUDES + k], modes.amplitude[k]);
}

TEST(StepWind, TheMeanFactorIsOneForASteadyWindAndFallsWithTheCycles) {
    EXPECT_EQ(detail::step_mean_factor(0.0), 1.0);
    EXPECT_NEAR(detail::step_mean_factor(0.5), 2.0 / std::numbers::pi, 1e-15);
    EXPECT_NEAR(detail::step_mean_factor(1.0), 0.0, 1e-15);
    EXPECT_EQ(detail::step_mean_factor(-0.25), detail::step_mean_factor(0.25));
}

}  // namespace
}  // namespace hmsm
