// The model's physics on the CPU oracle: rest pose, the analytic single-chain response, joint
// consistency and pointer jumping against serial composition.
#include "simulation_access.h"
#include "test_trees.h"

#include "backend.h"

#include <glm/gtc/matrix_transform.hpp>
#include <glm/matrix.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

using namespace hmsm;

namespace {

std::unique_ptr<Simulation> make(const Scene& scene, SimulationConfig config) {
    if (config.backend == BackendKind::automatic) config.backend = BackendKind::cpu64;
    auto sim = Simulation::create(scene, config);
    EXPECT_TRUE(sim.ok()) << sim.status().message();
    return sim.ok() ? std::move(sim).value() : nullptr;
}

}  // namespace

TEST(Physics, RestPoseIsReproducedWithOriginAndYaw) {
    TreeModel tree = test::small_tree();
    const glm::dvec3 origin(3.0, -1.0, 7.5);
    const double yaw = 0.7;
    SimulationConfig config;
    config.wind.profile = WindProfile::none;
    auto sim = make(single_tree_scene(tree, origin, yaw), config);
    ASSERT_TRUE(sim);
    glm::dmat3 ry(glm::rotate(glm::dmat4(1.0), yaw, glm::dvec3(0, 1, 0)));
    for (int steps : {0, 50}) {
        ASSERT_TRUE(sim->step(steps).ok());
        auto xyz = test::read_output(*sim, Output::node_positions);
        ASSERT_EQ(xyz.size(), 3 * tree.nodes.size());
        for (size_t n = 0; n < tree.nodes.size(); ++n) {
            glm::dvec3 expected = origin + ry * tree.nodes[n].position;
            for (int k = 0; k < 3; ++k)
                EXPECT_NEAR(xyz[3 * n + k], expected[k], 1e-12) << "node " << n << " after " << steps;
        }
    }
    // The mesh at rest is the template moved by the instance transform.
    auto vertices = test::read_output(*sim, Output::vertex_positions);
    const Hierarchy& h = sim->hierarchy(0);
    const MeshTemplate& mesh = sim->mesh(0);
    for (size_t v = 0; v < mesh.vertices.size(); ++v) {
        const Chain& chain = h.chains[mesh.vertices[v].chain];
        glm::dvec3 rest = tree.nodes[chain.attach_node].position + chain.frame * mesh.vertices[v].position;
        glm::dvec3 expected = origin + ry * rest;
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(vertices[3 * v + k], expected[k], 1e-12);
    }
}

// A single vertical chain under constant wind along x: the generalized force drives theta_z,
// g_z = -A s cos(theta_z) (the wind seen in the swaying frame), so the chain settles where
// K theta = -A s cos(theta), oscillating about it at the discrete frequency of symplectic
// Euler with an envelope decaying as exp(-zeta omega t).
TEST(Physics, SingleChainSettlesOscillatesAndDecaysAnalytically) {
    const double r = 0.2, L = 5.0;
    TreeModel tree = test::rod(4, L, r);
    SimulationConfig config;
    config.wind.profile = WindProfile::constant;
    config.wind.direction = {1, 0, 0};
    config.parameters.damping_ratio = 0.05;
    config.parameters.max_frequency = 10.0;  // the rod's 4.03 Hz stays below the cap
    const Parameters& p = config.parameters;
    const double K = p.stiffness * std::pow(r, 4) / L, I = p.density * r * r * L * L * L;
    const double A = p.wind_gain * r * L * L;
    config.wind.strength = 0.01 * K / A;  // small angle: about 0.01 rad
    auto sim = make(single_tree_scene(tree), config);
    ASSERT_TRUE(sim);
    ASSERT_FALSE(sim->hierarchy(0).chains[0].capped);

    double equilibrium = 0.0;  // solve K theta = -A s cos(theta)
    for (int i = 0; i < 50; ++i) equilibrium = -A * config.wind.strength * std::cos(equilibrium) / K;

    const double omega = std::sqrt(K / I), zeta = p.damping_ratio, dt = p.dt;
    std::vector<double> theta;
    const int steps = int(6.0 / dt);
    for (int n = 0; n < steps; ++n) {
        ASSERT_TRUE(sim->step(1).ok());
        auto angles = test::read_output(*sim, Output::chain_angles);
        EXPECT_NEAR(angles[0], 0.0, 1e-15);  // theta_x untouched by wind along x
        theta.push_back(angles[1]);
    }
    // Upward crossings of the equilibrium give the damped period.
    std::vector<double> crossings;
    for (size_t n = 1; n < theta.size(); ++n) {
        double a = theta[n - 1] - equilibrium, b = theta[n] - equilibrium;
        if (a < 0 && b >= 0) crossings.push_back((n - 1) + a / (a - b));
    }
    ASSERT_GE(crossings.size(), 4u);
    double period = (crossings.back() - crossings.front()) / double(crossings.size() - 1) * dt;
    double omega_damped = omega * std::sqrt(1 - zeta * zeta);
    EXPECT_NEAR(period, 2 * std::numbers::pi / omega_damped, 0.02 * 2 * std::numbers::pi / omega);
    // Successive maxima decay by exp(-zeta omega T).
    std::vector<double> peaks;
    for (size_t n = 1; n + 1 < theta.size(); ++n)
        if (theta[n] > theta[n - 1] && theta[n] >= theta[n + 1]) peaks.push_back(theta[n] - equilibrium);
    ASSERT_GE(peaks.size(), 4u);
    double expected_ratio = std::exp(-zeta * omega * period);
    EXPECT_NEAR(peaks[2] / peaks[1], expected_ratio, 0.03);
    // After many decay times it rests at the analytic angle.
    ASSERT_TRUE(sim->step(int(40.0 / dt)).ok());
    auto angles = test::read_output(*sim, Output::chain_angles);
    EXPECT_NEAR(angles[1], equilibrium, 1e-6 * std::abs(equilibrium));
    EXPECT_NEAR(equilibrium, -A * config.wind.strength / K, 1e-3 * std::abs(equilibrium));
}

TEST(Physics, AnglesAreClampedAtMaxAngle) {
    TreeModel tree = test::rod(4, 5.0, 0.2);
    SimulationConfig config;
    config.wind.profile = WindProfile::constant;
    config.wind.strength = 1e4;
    config.parameters.max_angle = 0.3;
    auto sim = make(single_tree_scene(tree), config);
    ASSERT_TRUE(sim);
    ASSERT_TRUE(sim->step(200).ok());
    auto angles = test::read_output(*sim, Output::chain_angles);
    EXPECT_NEAR(std::abs(angles[1]), 0.3, 1e-15);
}

// Every step, a child chain's origin is its attach node's world position (the parent
// chain's node), and each child's base ring stays centred on that joint.
TEST(Physics, ChildChainsStayAttachedEveryStep) {
    TreeModel tree = test::small_tree();
    SimulationConfig config;
    config.wind.strength = 40.0;
    config.wind.direction = {1, 0, 0.5};
    config.parameters.stiffness = 1e5;  // large swings
    auto sim = make(single_tree_scene(tree, {2, 0, 1}, 0.4), config);
    ASSERT_TRUE(sim);
    const Hierarchy& h = sim->hierarchy(0);
    const MeshTemplate& mesh = sim->mesh(0);
    double largest_angle = 0.0;
    for (int step = 0; step < 120; ++step) {
        ASSERT_TRUE(sim->step(1).ok());
        auto nodes = test::read_output(*sim, Output::node_positions);
        auto origins = test::read_output(*sim, Output::chain_origins);
        auto vertices = test::read_output(*sim, Output::vertex_positions);
        auto angles = test::read_output(*sim, Output::chain_angles);
        ASSERT_TRUE(test::all_finite(vertices));
        for (size_t c = 0; c < h.chains.size(); ++c)
            largest_angle = std::max({largest_angle, std::abs(angles[4 * c]), std::abs(angles[4 * c + 1])});
        size_t v = 0;
        for (size_t c = 0; c < h.chains.size(); ++c) {
            int32_t a = h.chains[c].attach_node;
            for (int k = 0; k < 3; ++k) EXPECT_NEAR(origins[3 * c + k], nodes[3 * a + k], 1e-12);
            glm::dvec3 centroid(0.0);
            for (int s = 0; s < 8; ++s)
                centroid += glm::dvec3(vertices[3 * (v + s)], vertices[3 * (v + s) + 1], vertices[3 * (v + s) + 2]);
            centroid /= 8.0;
            for (int k = 0; k < 3; ++k) EXPECT_NEAR(centroid[k], nodes[3 * a + k], 1e-9) << "chain " << c;
            v += 8 * (h.chains[c].members.size() + 1) + (h.continuation[h.chains[c].members.back()] < 0);
        }
        EXPECT_EQ(v + 4 * tree.leaves.size(), mesh.vertices.size());
    }
    EXPECT_GT(largest_angle, 0.05);  // the test exercised real swinging
}

TEST(Physics, PointerJumpingEqualsSerialComposition) {
    TreeModel tree = test::deep_tree(6);  // max depth 6: 3 rounds
    SimulationConfig config;
    config.wind.strength = 20.0;
    config.parameters.stiffness = 1e5;
    auto jump = make(single_tree_scene(tree, {1, 0, 0}, 0.3), config);
    config.composition = Composition::level_by_level;
    auto level = make(single_tree_scene(tree, {1, 0, 0}, 0.3), config);
    ASSERT_TRUE(jump && level);
    ASSERT_EQ(jump->hierarchy(0).max_depth, 6);
    EXPECT_EQ(jump->jump_rounds(), 3u);
    ASSERT_TRUE(jump->step(300).ok());
    ASSERT_TRUE(level->step(300).ok());
    for (Output o : {Output::chain_rotations, Output::chain_origins, Output::node_positions,
                     Output::vertex_positions}) {
        auto a = test::read_output(*jump, o), b = test::read_output(*level, o);
        EXPECT_LT(test::max_abs_difference(a, b), 1e-12) << int(o);
    }
    // And R_c equals the serial product of local transforms down the chain path.
    std::vector<double> local(12 * jump->chain_count());
    ASSERT_TRUE(hmsm::detail::backend_of(*jump).read(detail::BufferId::chain_local, 0, jump->chain_count(),
                                     local.data(), detail::Scalar::f64).ok());
    auto rotations = test::read_output(*jump, Output::chain_rotations);
    const Hierarchy& h = jump->hierarchy(0);
    auto t = [&](int c) {
        glm::dmat3 m;
        for (int col = 0; col < 3; ++col)
            for (int row = 0; row < 3; ++row) m[col][row] = local[12 * c + 4 * col + row];
        return m;
    };
    for (size_t c = 0; c < h.chains.size(); ++c) {
        glm::dmat3 serial = t(int(c));
        for (int p = h.chains[c].parent; p >= 0; p = h.chains[p].parent) serial = t(p) * serial;
        for (int col = 0; col < 3; ++col)
            for (int row = 0; row < 3; ++row)
                EXPECT_NEAR(rotations[9 * c + 3 * col + row], serial[col][row], 1e-12);
    }
}

TEST(Physics, FloatAgreesWithDouble) {
    TreeModel tree = test::small_tree();
    SimulationConfig config;
    config.wind.strength = 5.0;
    config.backend = BackendKind::cpu;
    auto single = make(single_tree_scene(tree, {0, 0, 0}, 0.2), config);
    config.backend = BackendKind::cpu64;
    auto oracle = make(single_tree_scene(tree, {0, 0, 0}, 0.2), config);
    ASSERT_TRUE(single && oracle);
    ASSERT_TRUE(single->step(1000).ok());
    ASSERT_TRUE(oracle->step(1000).ok());
    double height = tree_height(tree);
    EXPECT_LT(test::max_abs_difference(test::read_output(*single, Output::node_positions),
                                       test::read_output(*oracle, Output::node_positions)) / height, 1e-4);
    EXPECT_LT(test::max_abs_difference(test::read_output(*single, Output::vertex_positions),
                                       test::read_output(*oracle, Output::vertex_positions)) / height, 1e-4);
}

TEST(Simulation, RejectsBadConfigurationWithANamedError) {
    Scene scene = single_tree_scene(test::small_tree());
    SimulationConfig config;
    config.backend = BackendKind::cpu64;
    config.parameters.dt = 0;
    auto sim = Simulation::create(scene, config);
    ASSERT_FALSE(sim.ok());
    EXPECT_EQ(sim.status().code(), ErrorCode::invalid_argument);
    EXPECT_NE(sim.status().message().find("dt"), std::string::npos);
    config = {};
    config.model.ring_sides = 2;
    EXPECT_FALSE(Simulation::create(scene, config).ok());
    scene.instances[0].model = 3;
    EXPECT_FALSE(Simulation::create(scene, SimulationConfig{}).ok());
}
