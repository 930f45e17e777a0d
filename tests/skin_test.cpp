// Joint matrices and skin data (docs/model.md 3.10) on every backend: Output::joint_matrices is
// [R_c | O_c] of the chain outputs in every composition; a linear-blend skin evaluated on the
// CPU from the joint matrices and build_skin() reproduces pass 7's vertices and normals; outputs
// on demand skip passes 6 and 7 without changing the joints.
#include "simulation_access.h"
#include "test_compositions.h"
#include "test_trees.h"

#include "backend.h"

#include <hmsm/skin.h>

#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include <cmath>

using namespace hmsm;

namespace {

double scene_height(const Scene& scene) {
    double h = 0.0;
    for (const TreeModel& m : scene.models) h = std::max(h, tree_height(m));
    return h;
}

/// Two models in four instance groups, with origins and yaws.
Scene mixed_scene() {
    Scene mixed;
    mixed.models = {test::small_tree(), test::deep_tree(5)};
    mixed.model_names = {"small", "deep"};
    mixed.instances = {{1, {0, 0, 0}, 0.0}, {0, {5, 0, 1}, 0.5}, {0, {-4, 0, 3}, 2.0}, {1, {2, 0, -6}, -0.7}};
    return mixed;
}

SimulationConfig windy() {
    SimulationConfig config;
    config.wind.strength = 8.0;
    config.wind.direction = {1, 0, 0.3};
    return config;
}

/// p' = M (p, 1) for a 3x4 matrix given row by row.
glm::dvec3 transform(const double* m, const glm::dvec3& p) {
    return {m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3], m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
            m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11]};
}
glm::dvec3 rotate(const double* m, const glm::dvec3& v) {
    return {m[0] * v.x + m[1] * v.y + m[2] * v.z, m[4] * v.x + m[5] * v.y + m[6] * v.z,
            m[8] * v.x + m[9] * v.y + m[10] * v.z};
}

/// Linear-blend skinning of every instance's bind-pose mesh from the joint matrices, as an
/// engine's vertex shader does it (shaders/glsl/skinning.glsl): positions and normals, xyz per
/// vertex, instance-major.
void skin_on_cpu(const Simulation& sim, const std::vector<double>& joints, std::vector<double>& positions,
                 std::vector<double>& normals) {
    std::vector<SkinTemplate> skins;
    for (uint32_t m = 0; m < sim.scene().models.size(); ++m)
        skins.push_back(build_skin(sim.scene().models[m], sim.hierarchy(m), sim.mesh(m), sim.config().model));
    positions.clear();
    normals.clear();
    uint64_t chain_base = 0;
    for (const Instance& inst : sim.instances()) {
        const SkinTemplate& skin = skins[inst.model];
        for (const SkinVertex& v : skin.vertices) {
            glm::dvec3 p(0.0), n(0.0);
            for (int j = 0; j < 2; ++j) {
                if (v.joints[j] < 0) continue;
                const double* m = &joints[12 * (chain_base + uint64_t(v.joints[j]))];
                const double* inv = skin.inverse_bind[v.joints[j]].data();
                p += v.weights[j] * transform(m, transform(inv, glm::dvec3(v.position)));
                n += v.weights[j] * rotate(m, rotate(inv, glm::dvec3(v.normal)));
            }
            n = glm::normalize(n);
            positions.insert(positions.end(), {p.x, p.y, p.z});
            normals.insert(normals.end(), {n.x, n.y, n.z});
        }
        chain_base += sim.hierarchy(inst.model).chains.size();
    }
}

class Joints : public ::testing::TestWithParam<BackendKind> {};

/// Output::joint_matrices holds R_c and O_c of the chain outputs, in the documented order, in
/// every composition (the window of the final root_positions writes differs per composition),
/// and agrees with the cpu64 oracle.
TEST_P(Joints, JointMatricesAreRotationsAndOriginsInEveryComposition) {
    const Scene scene = mixed_scene();
    const double height = scene_height(scene);
    for (test::TestComposition composition : test::kEveryComposition) {
        SCOPED_TRACE(test::name_of(composition));
        SimulationConfig config = windy();
        config.composition = composition.composition;
        std::string skip;
        auto sim = test::create_simulation_or_skip(scene, config, GetParam(), skip, composition.jumping_form);
        if (!skip.empty()) GTEST_SKIP() << skip;
        auto oracle = test::create_simulation_or_skip(scene, config, BackendKind::cpu64, skip);
        ASSERT_TRUE(sim && oracle);
        ASSERT_TRUE(sim->step(150).ok());
        ASSERT_TRUE(oracle->step(150).ok());
        auto joints = test::read_output(*sim, Output::joint_matrices);
        auto rotations = test::read_output(*sim, Output::chain_rotations);
        auto origins = test::read_output(*sim, Output::chain_origins);
        ASSERT_EQ(joints.size(), 12 * sim->chain_count());
        for (uint64_t c = 0; c < sim->chain_count(); ++c) {
            for (int i = 0; i < 3; ++i) {
                for (int j = 0; j < 3; ++j)  // rotations are column-major: element (i, j) at 3j + i
                    ASSERT_EQ(joints[12 * c + 4 * i + j], rotations[9 * c + 3 * j + i]) << "chain " << c;
                ASSERT_EQ(joints[12 * c + 4 * i + 3], origins[3 * c + i]) << "chain " << c;
            }
        }
        auto expected = test::read_output(*oracle, Output::joint_matrices);
        EXPECT_LE(test::max_abs_difference(joints, expected) / std::max(1.0, height), 1e-4);
        // The pose moved away from rest.
        auto rest = test::create_simulation_or_skip(scene, config, BackendKind::cpu64, skip);
        EXPECT_GT(test::max_abs_difference(test::read_output(*rest, Output::joint_matrices), expected), 1e-3);
    }
}

/// The skin reproduces pass 7: positions within 1e-5 of the tree height, normals within 1e-4,
/// for contour fix-up weights with two joints (0.5, 0.3) and one (0, 1).
TEST_P(Joints, SkinnedVerticesEqualContourVertices) {
    const Scene scene = mixed_scene();
    const double height = scene_height(scene);
    for (double beta : {0.5, 0.3, 0.0, 1.0}) {
        SCOPED_TRACE("fix_weight " + std::to_string(beta));
        SimulationConfig config = windy();
        config.model.fix_weight = beta;
        std::string skip;
        auto sim = test::create_simulation_or_skip(scene, config, GetParam(), skip);
        if (!skip.empty()) GTEST_SKIP() << skip;
        ASSERT_TRUE(sim);
        ASSERT_TRUE(sim->step(200).ok());
        std::vector<double> positions, normals;
        skin_on_cpu(*sim, test::read_output(*sim, Output::joint_matrices), positions, normals);
        auto contour = test::read_output(*sim, Output::vertex_positions);
        ASSERT_EQ(positions.size(), contour.size());
        EXPECT_LE(test::max_abs_difference(positions, contour) / height, 1e-5);
        EXPECT_LE(test::max_abs_difference(normals, test::read_output(*sim, Output::vertex_normals)), 1e-4);
    }
}

/// Outputs on demand: joints only dispatches passes 1-5, joints and nodes 1-6; the joint
/// matrices (and nodes) are those of a simulation producing everything, bit for bit; outputs
/// not produced are refused with a clear error and have no device elements.
TEST_P(Joints, OutputsOnDemandSkipPassesAndKeepTheJoints) {
    const Scene scene = mixed_scene();
    SimulationConfig config = windy();
    std::string skip;
    auto all = test::create_simulation_or_skip(scene, config, GetParam(), skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(all && all->step(60).ok());
    for (Outputs outputs : {Outputs::joints, Outputs::joints_and_nodes}) {
        SCOPED_TRACE(to_string(outputs));
        config.outputs = outputs;
        auto sim = test::create_simulation_or_skip(scene, config, GetParam(), skip);
        ASSERT_TRUE(sim && sim->step(60).ok());
        bool has_node_world = false, has_contour = false, has_root_positions = false;
        for (const auto& d : detail::step_program_of(*sim)) {  // (a path-walk dispatch runs two passes)
            const uint32_t passes = detail::dispatch_passes(d);
            has_node_world |= (passes >> uint32_t(Pass::node_world) & 1u) != 0;
            has_contour |= (passes >> uint32_t(Pass::contour) & 1u) != 0;
            has_root_positions |= (passes >> uint32_t(Pass::root_positions) & 1u) != 0;
        }
        EXPECT_TRUE(has_root_positions);
        EXPECT_FALSE(has_contour);
        EXPECT_EQ(has_node_world, outputs == Outputs::joints_and_nodes);
        EXPECT_EQ(detail::scene_data_of(*sim).element_count(detail::BufferId::vertex_position), 0u);
        EXPECT_EQ(test::read_output(*sim, Output::joint_matrices), test::read_output(*all, Output::joint_matrices));
        std::vector<float> values;
        Status refused = sim->read(Output::vertex_positions, values);
        EXPECT_EQ(refused.code(), ErrorCode::invalid_argument);
        EXPECT_NE(refused.message().find("vertex_positions"), std::string::npos) << refused.message();
        if (outputs == Outputs::joints_and_nodes) {
            EXPECT_EQ(test::read_output(*sim, Output::node_positions), test::read_output(*all, Output::node_positions));
        } else {
            EXPECT_EQ(sim->read(Output::node_positions, values).code(), ErrorCode::invalid_argument);
        }
    }
}

INSTANTIATE_TEST_SUITE_P(Backends, Joints,
                         ::testing::Values(BackendKind::cpu, BackendKind::cpu64, BackendKind::vulkan,
                                           BackendKind::cuda),
                         test::BackendTestName());

/// The bind pose: at rest an instance at the origin with yaw 0 has M_c = [B_c | p̄_attach(c)],
/// the skin's bind matrices, and bind positions are pass 7's rest vertices.
TEST(Skin, BindPoseIsTheRestPose) {
    const TreeModel tree = test::small_tree();
    SimulationConfig config;
    config.backend = BackendKind::cpu64;
    auto sim = Simulation::create(single_tree_scene(tree), config);
    ASSERT_TRUE(sim.ok()) << sim.status().message();
    const Simulation& s = **sim;
    SkinTemplate skin = build_skin(tree, s.hierarchy(0), s.mesh(0), config.model);
    ASSERT_EQ(skin.vertices.size(), s.mesh(0).vertices.size());
    ASSERT_EQ(skin.inverse_bind.size(), s.hierarchy(0).chains.size());
    auto joints = test::read_output(s, Output::joint_matrices);
    for (size_t c = 0; c < skin.bind.size(); ++c) {
        for (int k = 0; k < 12; ++k) EXPECT_NEAR(joints[12 * c + k], skin.bind[c][k], 1e-12) << c;
        // inverse_bind * bind = identity
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 4; ++j) {
                double v = 0.0;
                for (int k = 0; k < 3; ++k) v += skin.inverse_bind[c][4 * i + k] * skin.bind[c][4 * k + j];
                if (j == 3) v += skin.inverse_bind[c][4 * i + 3];
                EXPECT_NEAR(v, i == j ? 1.0 : 0.0, 1e-12);
            }
    }
    auto rest = test::read_output(s, Output::vertex_positions);
    auto rest_normals = test::read_output(s, Output::vertex_normals);
    uint32_t two_joint = 0;
    for (size_t v = 0; v < skin.vertices.size(); ++v) {
        const SkinVertex& sv = skin.vertices[v];
        for (int k = 0; k < 3; ++k) {
            EXPECT_NEAR(sv.position[k], rest[3 * v + k], 1e-12);
            EXPECT_NEAR(sv.normal[k], rest_normals[3 * v + k], 1e-12);
        }
        EXPECT_NEAR(sv.weights[0] + sv.weights[1], 1.0, 1e-15);
        const MeshVertex& mv = s.mesh(0).vertices[v];
        EXPECT_EQ(sv.joints[0], mv.chain);
        if (sv.joints[1] >= 0) {
            ++two_joint;
            EXPECT_EQ(sv.joints[1], mv.fix_chain);
            EXPECT_DOUBLE_EQ(sv.weights[1], config.model.fix_weight);
        }
    }
    // Every non-trunk chain's base ring has two joints.
    EXPECT_EQ(two_joint, (s.hierarchy(0).chains.size() - 1) * uint32_t(config.model.ring_sides));
}

}  // namespace
