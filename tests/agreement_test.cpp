// The end-to-end agreement suite, written once and run per backend: every backend against the
// cpu64 oracle after many steps (docs/model.md 7); each pass alone on random states is
// agreement/pass_agreement_test.cpp. A backend that is not compiled in or has no device is
// skipped with the reason.
#include "simulation_access.h"
#include "test_compositions.h"
#include "test_trees.h"

#include "backend.h"
#include "common/octahedral.h"

#include <hmsm/generator.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

using namespace hmsm;
using detail::BufferId;

namespace {

struct SceneCase {
    std::string name;
    Scene scene;
    SimulationConfig config;
};

std::vector<SceneCase> end_to_end_cases() {
    std::vector<SceneCase> cases;
    SimulationConfig windy;
    windy.wind.strength = 8.0;
    windy.wind.direction = {1, 0, 0.3};
    windy.parameters.wind_gain = 15.0;  // a storm: large angles, the clamp reached at times
    cases.push_back({"small_tree", single_tree_scene(test::small_tree()), windy});
    cases.push_back({"deep_tree_origin_yaw", single_tree_scene(test::deep_tree(6), {3, 1, -2}, 1.1), windy});
    auto grid = grid_scene(test::small_tree(), 7, 6.0, 42);
    cases.push_back({"grid_of_7", *grid, windy});
    // More instances than a packed contour thread places (HMSM_PACKED_CONTOUR_INSTANCES, 8), and
    // not a multiple of it.
    cases.push_back({"grid_of_19", *grid_scene(test::small_tree(), 19, 6.0, 5), windy});
    Scene mixed;
    mixed.models = {test::small_tree(), test::rod(5, 4.0, 0.15)};
    mixed.model_names = {"small", "rod"};
    mixed.instances = {{1, {0, 0, 0}, 0.0}, {0, {5, 0, 1}, 0.5}, {0, {-4, 0, 3}, 2.0}, {1, {2, 0, -6}, -0.7}};
    cases.push_back({"two_models_four_groups", mixed, windy});
    SimulationConfig width = windy;
    width.model.grouping = Grouping::width;
    cases.push_back({"width_grouping", single_tree_scene(test::small_tree()), width});
    SimulationConfig cut = windy;
    cut.model.max_chain_segments = 2;
    cut.model.ring_sides = 5;
    cases.push_back({"cut_chains_5_sides", single_tree_scene(test::small_tree(), {1, 0, 1}, 0.3), cut});
    SimulationConfig level = windy;
    level.composition = Composition::level_by_level;
    cases.push_back({"level_by_level", single_tree_scene(test::deep_tree(5), {0, 0, 0}, 0.2), level});
    SimulationConfig walk = windy;
    walk.composition = Composition::path_walk;
    cases.push_back({"path_walk", *grid_scene(test::deep_tree(6), 3, 9.0, 11), walk});
    // Deeper than the walk records hold ancestors of (HMSM_WALK_PATH_CAPACITY, 15): the rest looked up.
    // A breeze: in the storm float and double part on its hair-thin top chains.
    walk.parameters.wind_gain = 2.0;
    cases.push_back({"path_walk_deep", single_tree_scene(test::deep_tree(19), {1, 0, -1}, 0.7), walk});
    SimulationConfig front = windy;
    front.wind.profile = WindProfile::y2;
    front.wind.front_speed = 3.0;
    front.wind.frequency = 0.4;
    cases.push_back({"travelling_front_y2", *grid_scene(test::deep_tree(3), 5, 9.0, 7), front});
    // The atmospheric wind field: a vector per instance that differs across the forest; 19
    // instances (not a multiple of any workgroup or block) in pointer jumping and the path walk.
    SimulationConfig atmospheric = windy;
    atmospheric.wind.profile = WindProfile::atmospheric;
    atmospheric.wind.turbulence = 0.8;
    atmospheric.wind.seed = 2024;
    atmospheric.parameters.wind_gain = 6.0;
    cases.push_back({"atmospheric_grid_of_19", *grid_scene(test::small_tree(), 19, 4.0, 3), atmospheric});
    atmospheric.composition = Composition::path_walk;
    atmospheric.wind.direction = {-1, 0.2, 2};
    cases.push_back({"atmospheric_path_walk", *grid_scene(test::deep_tree(5), 7, 7.0, 13), atmospheric});
    return cases;
}

double scene_height(const Scene& scene) {
    double h = 0.0;
    for (const TreeModel& m : scene.models) h = std::max(h, tree_height(m));
    return h;
}

class Agreement : public ::testing::TestWithParam<BackendKind> {};

TEST_P(Agreement, EndToEndAfter1000Steps) {
    for (SceneCase& c : end_to_end_cases()) {
        SCOPED_TRACE(c.name);
        std::string skip;
        auto sim = test::create_simulation_or_skip(c.scene, c.config, GetParam(), skip);
        if (!skip.empty()) GTEST_SKIP() << skip;
        auto oracle = test::create_simulation_or_skip(c.scene, c.config, BackendKind::cpu64, skip);
        ASSERT_TRUE(sim && oracle);
        ASSERT_TRUE(sim->step(400).ok());
        ASSERT_TRUE(sim->step(600).ok());
        ASSERT_TRUE(oracle->step(1000).ok());
        const double height = scene_height(c.scene);
        for (Output o : {Output::node_positions, Output::vertex_positions}) {
            auto a = test::read_output(*sim, o), b = test::read_output(*oracle, o);
            ASSERT_EQ(a.size(), b.size());
            EXPECT_LE(test::max_abs_difference(a, b) / height, 1e-4) << "output " << int(o);
        }
        auto normals = test::read_output(*sim, Output::vertex_normals);
        EXPECT_LE(test::max_abs_difference(normals, test::read_output(*oracle, Output::vertex_normals)), 1e-3);
        // The scene really moved: positions differ from the rest pose.
        auto rest = test::create_simulation_or_skip(c.scene, c.config, BackendKind::cpu64, skip);
        EXPECT_GT(test::max_abs_difference(test::read_output(*rest, Output::node_positions),
                                           test::read_output(*oracle, Output::node_positions)),
                  1e-3 * height);
    }
}

/// VertexLayout::packed on every backend: the same positions as the separate layout, bit for
/// bit; normals decoded from the positions' w within the quantization of the separate layout's
/// and within 1e-3 of the cpu64 oracle; the word itself the C++ encoder's for that normal; and
/// no vertex_normal elements on the device.
TEST_P(Agreement, PackedVertexLayoutAfter300Steps) {
    auto cases = end_to_end_cases();
    for (SceneCase& c : cases) {
        if (c.name != "small_tree" && c.name != "two_models_four_groups" && c.name != "level_by_level" &&
            c.name != "grid_of_19")
            continue;
        SCOPED_TRACE(c.name);
        SimulationConfig packed_config = c.config;
        packed_config.vertex_layout = VertexLayout::packed;
        std::string skip;
        auto packed = test::create_simulation_or_skip(c.scene, packed_config, GetParam(), skip);
        if (!skip.empty()) GTEST_SKIP() << skip;
        auto separate = test::create_simulation_or_skip(c.scene, c.config, GetParam(), skip);
        auto oracle = test::create_simulation_or_skip(c.scene, c.config, BackendKind::cpu64, skip);
        ASSERT_TRUE(packed && separate && oracle);
        for (auto* sim : {packed.get(), separate.get(), oracle.get()}) ASSERT_TRUE(sim->step(300).ok());

        // The contour dispatches carry the layout; the normal buffer has no elements.
        for (const auto& d : hmsm::detail::step_program_of(*packed))
            if (d.pass == Pass::contour) EXPECT_EQ(d.constants.kind, HMSM_DISPATCH_CONTOUR_PACKED);
        EXPECT_EQ(hmsm::detail::scene_data_of(*packed).element_count(BufferId::vertex_normal), 0u);
        EXPECT_EQ(hmsm::detail::scene_data_of(*separate).element_count(BufferId::vertex_normal), separate->vertex_count());
        float unused[4];
        EXPECT_FALSE(hmsm::detail::backend_of(*packed).read(BufferId::vertex_normal, 0, 1, unused, detail::Scalar::f32).ok());

        std::vector<float> packed_positions, separate_positions;
        ASSERT_TRUE(packed->read(Output::vertex_positions, packed_positions).ok());
        ASSERT_TRUE(separate->read(Output::vertex_positions, separate_positions).ok());
        EXPECT_EQ(packed_positions, separate_positions);
        std::vector<float> packed_nodes, separate_nodes;
        ASSERT_TRUE(packed->read(Output::node_positions, packed_nodes).ok());
        ASSERT_TRUE(separate->read(Output::node_positions, separate_nodes).ok());
        EXPECT_EQ(packed_nodes, separate_nodes);

        auto normals = test::read_output(*packed, Output::vertex_normals);
        auto separate_normals = test::read_output(*separate, Output::vertex_normals);
        ASSERT_EQ(normals.size(), 3 * packed->vertex_count());
        EXPECT_LE(test::max_abs_difference(normals, test::read_output(*oracle, Output::vertex_normals)), 1e-3);
        EXPECT_LE(test::max_abs_difference(normals, separate_normals), 1e-4);
        std::vector<float> normals_f32;
        ASSERT_TRUE(packed->read(Output::vertex_normals, normals_f32).ok());
        EXPECT_LE(test::max_abs_difference(std::vector<double>(normals_f32.begin(), normals_f32.end()), normals), 1e-6);

        // The stored word is the C++ encoder's word for the separate layout's normal, each
        // snorm16 half within one step: GLSL float division need not be correctly rounded, so a
        // GPU driver may round a component the other way (1 of 488 words on the NVIDIA driver;
        // bit for bit on the CPU and lavapipe).
        std::vector<float> raw(4 * packed->vertex_count()), separate_raw(4 * packed->vertex_count());
        ASSERT_TRUE(hmsm::detail::backend_of(*packed).read(BufferId::vertex_position, 0, packed->vertex_count(), raw.data(), detail::Scalar::f32).ok());
        ASSERT_TRUE(hmsm::detail::backend_of(*separate).read(BufferId::vertex_normal, 0, separate->vertex_count(), separate_raw.data(), detail::Scalar::f32).ok());
        uint64_t differing = 0;
        for (uint64_t v = 0; v < packed->vertex_count(); ++v) {
            const uint32_t expected = detail::encode_normal_word(separate_raw[4 * v], separate_raw[4 * v + 1], separate_raw[4 * v + 2]);
            const uint32_t stored = detail::bits_from_float(raw[4 * v + 3]);
            auto half = [](uint32_t word, int k) { return int32_t(int16_t(uint16_t(word >> (16 * k)))); };
            for (int k = 0; k < 2; ++k)
                if (std::abs(half(stored, k) - half(expected, k)) > 1) ++differing;
        }
        EXPECT_EQ(differing, 0u) << "of " << packed->vertex_count() << " vertices";
    }
}

TEST(AgreementOracle, PackedVertexLayoutOnCpu64) {
    SimulationConfig config;
    config.wind.strength = 8.0;
    config.vertex_layout = VertexLayout::packed;
    Scene scene = *grid_scene(test::small_tree(), 3, 6.0, 5);
    std::string skip;
    auto packed = test::create_simulation_or_skip(scene, config, BackendKind::cpu64, skip);
    config.vertex_layout = VertexLayout::separate;
    auto separate = test::create_simulation_or_skip(scene, config, BackendKind::cpu64, skip);
    ASSERT_TRUE(packed && separate);
    ASSERT_TRUE(packed->step(200).ok());
    ASSERT_TRUE(separate->step(200).ok());
    EXPECT_EQ(test::read_output(*packed, Output::vertex_positions), test::read_output(*separate, Output::vertex_positions));
    auto normals = test::read_output(*packed, Output::vertex_normals);
    EXPECT_LE(test::max_abs_difference(normals, test::read_output(*separate, Output::vertex_normals)), 1e-4);
    std::vector<float> normals_f32;
    ASSERT_TRUE(packed->read(Output::vertex_normals, normals_f32).ok());
    EXPECT_LE(test::max_abs_difference(std::vector<double>(normals_f32.begin(), normals_f32.end()), normals), 1e-6);
}

TEST_P(Agreement, RoundsInOneDispatchMatchOneDispatchPerRound) {
    // In-dispatch pointer jumping (a workgroup per instance loops over its chains round by
    // round) must give the per-round result. paper-1 has 2,345 chains, more than one workgroup
    // (1,024) covers at once; the mixed scene has two models in several instance groups.
    auto paper = generate_preset("paper-1");
    ASSERT_TRUE(paper.ok());
    Scene mixed = *grid_scene(test::small_tree(), 3, 5.0, 3);
    mixed.models.push_back(test::deep_tree(6));
    mixed.model_names.push_back("deep");
    mixed.instances.push_back({1, {-3, 0, 2}, 0.8});
    mixed.instances.push_back({0, {6, 0, -2}, 0.1});
    for (const auto& [name, scene] : {std::pair{"paper-1", single_tree_scene(*paper, {1, 0, 2}, 0.4)},
                                      std::pair{"mixed", mixed}}) {
        SCOPED_TRACE(name);
        SimulationConfig config;
        config.wind.strength = 8.0;
        config.composition = Composition::pointer_jumping;
        std::string skip;
        auto one = test::create_simulation_or_skip(scene, config, GetParam(), skip, detail::JumpingForm::in_dispatch);
        if (!skip.empty()) GTEST_SKIP() << skip;
        auto per_round = test::create_simulation_or_skip(scene, config, GetParam(), skip, detail::JumpingForm::per_round);
        ASSERT_TRUE(one && per_round);
        uint32_t in_dispatch = 0;
        for (const auto& d : hmsm::detail::step_program_of(*one))
            in_dispatch += d.constants.kind == HMSM_DISPATCH_JUMP_ROUNDS_IN_DISPATCH;
        EXPECT_GT(in_dispatch, 0u);
        ASSERT_TRUE(one->step(40).ok());
        ASSERT_TRUE(per_round->step(40).ok());
        const double height = scene_height(scene);
        for (Output o : {Output::chain_rotations, Output::chain_origins, Output::node_positions,
                         Output::vertex_positions}) {
            auto a = test::read_output(*one, o), b = test::read_output(*per_round, o);
            ASSERT_EQ(a.size(), b.size());
            ASSERT_TRUE(test::all_finite(a));
            const double scale = o == Output::chain_rotations ? 1.0 : height;
            EXPECT_LE(test::max_abs_difference(a, b) / scale, 1e-6) << "output " << int(o);
        }
    }
}

INSTANTIATE_TEST_SUITE_P(Backends, Agreement,
                         ::testing::Values(BackendKind::cpu, BackendKind::cpu_parallel, BackendKind::vulkan,
                                           BackendKind::cuda),
                         test::BackendTestName());

}  // namespace
