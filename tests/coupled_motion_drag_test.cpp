// The drag of a chain's own motion in still air (docs/model.md 3.13, aerodynamic damping): the
// constant against the rod's closed form, and a released rod whose swing decays faster the
// larger it is, against the same rod without drag, whose decay does not depend on its size.
#include "simulation_access.h"
#include "test_trees.h"

#include "model/coupled_constants.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

using namespace hmsm;

namespace {

constexpr double kLength = 5.0, kRadius = 0.02;  // a slender rod: 0.7 Hz, drag weighs

/// The damping ratio of the rod's free sway in calm air from the angle `angle` (rad) about z,
/// at rest: the mean logarithmic decrement of its first four half swings over pi.
double release_damping_ratio(const Parameters& parameters, double angle) {
    SimulationConfig config = test::coupled_config();
    config.parameters = parameters;
    config.wind.profile = WindProfile::none;
    auto sim = Simulation::create(single_tree_scene(test::rod(1, kLength, kRadius)), config);
    EXPECT_TRUE(sim.ok()) << sim.status().message();
    if (!sim.ok()) return 0.0;
    const double state[4] = {0.0, angle, 0.0, 0.0};  // (theta_x, theta_z, V_x, V_z)
    EXPECT_TRUE(detail::backend_of(**sim).write(detail::BufferId::chain_state, 0, 1, state, detail::Scalar::f64).ok());
    std::vector<double> theta;
    for (int i = 0; i < 600; ++i) {
        EXPECT_TRUE((*sim)->step(1).ok());
        theta.push_back(test::read_output(**sim, Output::chain_angles)[1]);
    }
    std::vector<double> peaks;  // |theta| at each extremum, half a period apart
    for (size_t i = 1; i + 1 < theta.size() && peaks.size() < 5; ++i)
        if (std::abs(theta[i]) >= std::abs(theta[i - 1]) && std::abs(theta[i]) > std::abs(theta[i + 1]))
            peaks.push_back(std::abs(theta[i]));
    EXPECT_EQ(peaks.size(), 5u);
    if (peaks.size() < 5) return 0.0;
    return std::log(peaks.front() / peaks.back()) / (4.0 * std::numbers::pi);
}

}  // namespace

// A rod along y: the drag area 2 r C_w per metre at distance y from either axis gives
// (1/2) rho C_w 2 r L^4 / 4 (the Gauss rule is exact for the cubic).
TEST(CoupledConstants, MotionDragIsHalfTheAirDensityTimesTheThirdDragMoment) {
    ModelOptions options;
    options.dynamics = Dynamics::coupled;
    Parameters parameters;
    auto h = build_hierarchy(test::rod(1, kLength, kRadius), options, parameters);
    ASSERT_TRUE(h.ok()) << h.status().message();
    const ChainDynamics& d = h->chains[0].dynamics;
    const double expected = 0.5 * detail::kAirDensity * parameters.wood_drag_coefficient * 2.0 * kRadius *
                            std::pow(kLength, 4) / 4.0;
    for (int a = 0; a < 2; ++a) EXPECT_NEAR(d.motion_drag[a], expected, 1e-9 * expected) << "axis " << a;
    parameters.wood_drag_coefficient = 0.0;
    auto bare = build_hierarchy(test::rod(1, kLength, kRadius), options, parameters);
    ASSERT_TRUE(bare.ok());
    EXPECT_EQ(bare->chains[0].dynamics.motion_drag[0], 0.0);
}

// Released in calm air, a rod that meets the air loses more of a large swing per cycle than of a
// small one (quadratic drag), and more than the structural damping alone; without drag the
// decay is the structural zeta_s at any size.
TEST(Coupled, MotionDragDampsALargerSwingMoreInCalmAir) {
    Parameters parameters;
    const double zeta_s = parameters.structural_damping;
    const double large = release_damping_ratio(parameters, 0.3);
    const double small = release_damping_ratio(parameters, 0.003);
    EXPECT_GT(large, zeta_s + 0.005) << "large " << large;
    EXPECT_NEAR(small, zeta_s, 0.002);
    Parameters still = parameters;
    still.wood_drag_coefficient = 0.0;
    EXPECT_NEAR(release_damping_ratio(still, 0.3), zeta_s, 0.002);
    EXPECT_NEAR(release_damping_ratio(still, 0.003), zeta_s, 0.002);
}
