// The coupled dynamics' per-chain record (src/common/gpu_layout.h HMSM_CHAIN_DYNAMICS_VEC4S),
// whose quotients are folded on the host and whose last vec4 holds the rows of Q that pass a
// child's load on: the shared math (src/common/coupled_math.h) on the record of every chain of
// a preset equals the forms of docs/model.md 3.13 evaluated from the hierarchy's constants.
#include "simulation_access.h"

#include "common/coupled_math.h"
#include "model/coupled_constants.h"

#include <hmsm/generator.h>

#include <gtest/gtest.h>

#include <cmath>

using namespace hmsm;

namespace {

TEST(CoupledRecord, SharedMathOnTheRecordEqualsTheModelsForms) {
    auto preset = generate_preset("paper-5");
    ASSERT_TRUE(preset.ok());
    SimulationConfig config;
    config.backend = BackendKind::cpu64;
    config.model.dynamics = Dynamics::coupled;
    auto sim = Simulation::create(single_tree_scene(*preset), config);
    ASSERT_TRUE(sim.ok()) << sim.status().message();
    const detail::SceneData& d = detail::scene_data_of(**sim);
    const Hierarchy& h = (*sim)->hierarchy(0);
    const double dt = d.dt;
    constexpr size_t kScalars = 4 * HMSM_CHAIN_DYNAMICS_VEC4S;
    ASSERT_EQ(d.chain_dynamics.size(), kScalars * h.chains.size());
    uint32_t with_children = 0;
    for (size_t c = 0; c < h.chains.size(); ++c) {
        SCOPED_TRACE("chain " + std::to_string(c));
        const double* record = d.chain_dynamics.data() + kScalars * c;
        const ChainDynamics& k = h.chains[c].dynamics;
        int32_t first = -1, count = -1;
        detail::coupled_children(record, first, count);
        EXPECT_EQ(first, k.first_child);
        EXPECT_EQ(count, k.child_count);
        with_children += count > 0 ? 1 : 0;
        // The chain's load (x, z) as its parent receives it: Q (L.x, 0, L.z), its x and z.
        const double load_x = 0.3 + 0.01 * double(c), load_z = -0.7;
        double g[2] = {0.0, 0.0};
        detail::coupled_add_child_load(record + 4 * HMSM_CHAIN_DYNAMICS_PASSING, load_x, load_z, g);
        const Vec3 passed = h.chains[c].rest_rotation * Vec3(load_x, 0.0, load_z);
        EXPECT_NEAR(g[0], passed.x, 1e-14);
        EXPECT_NEAR(g[1], passed.z, 1e-14);
        // Aerodynamic damping D sigma V, D = aero sqrt(|w|), sigma = (1 - exp(-x)) / x with
        // x = D dt / I (1 - x / 2 where x is tiny): a gale and a breath of wind.
        for (double wind_dot : {36.0, 1e-30}) {
            const double rate[2] = {0.4, -1.1};
            double damped[2] = {0.0, 0.0};
            detail::coupled_subtract_aero_damping(record, wind_dot, rate, damped);
            for (int a = 0; a < 2; ++a) {
                const double eta = (k.motion_drag[0] + k.motion_drag[1]) / (k.aero_damping[0] + k.aero_damping[1]);
                const double damping = k.aero_damping[a] * (std::sqrt(std::sqrt(wind_dot)) + eta * std::abs(rate[a]));
                const double x = damping * dt / k.inertia[a];
                const double share = x > 1e-4 ? (1.0 - std::exp(-x)) / x : 1.0 - 0.5 * x;
                const double expected = -damping * share * rate[a];
                EXPECT_NEAR(damped[a], expected, 1e-12 * std::abs(expected)) << "axis " << a << ", |w|^2 " << wind_dot;
            }
        }
        // The exact step about each axis: the offset from g / K turns by the transition.
        for (uint32_t a = 0; a < 2; ++a) {
            const auto phi = detail::oscillator_transition(k.inertia[a], k.stiffness[a], k.damping[a], dt);
            const double force = 0.02 * k.stiffness[a], angle0 = 0.05, rate0 = -0.3;
            double angle = angle0, rate = rate0;
            detail::coupled_step_axis(record, a, force, 10.0, angle, rate);
            const double equilibrium = force / k.stiffness[a], offset = angle0 - equilibrium;
            EXPECT_NEAR(angle, equilibrium + phi[0] * offset + phi[1] * rate0, 1e-12) << "axis " << a;
            EXPECT_NEAR(rate, phi[2] * offset + phi[3] * rate0, 1e-12 * (1.0 + std::abs(phi[2]))) << "axis " << a;
        }
    }
    EXPECT_GT(with_children, 10u);
}

}  // namespace
