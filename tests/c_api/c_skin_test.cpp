// Skins through the C ABI and CPU skinning (include/hmsm/hmsm_c.h "skins", hmsm::skin_vertices):
// the C reads give exactly hmsm::build_skin()'s data; skinning paper-1's bind mesh with a
// simulation's joint matrices reproduces the simulation's own pass-7 vertices; bad arguments
// fail with a message and write nothing.
#include <hmsm/hmsm.h>
#include <hmsm/hmsm_c.h>
#include <hmsm/skin.h>

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

using namespace hmsm;

namespace {

/// Two paper-1 trees, the second moved and turned, on the CPU backend in a constant wind.
struct Paper1 {
    hmsm_simulation* c = nullptr;
    hmsm_skin* skin = nullptr;
    ~Paper1() {
        hmsm_skin_destroy(skin);
        hmsm_simulation_destroy(c);
    }
};

void make_paper1(Paper1& out) {
    hmsm_tree* tree = nullptr;
    hmsm_scene* scene = nullptr;
    ASSERT_EQ(hmsm_tree_preset("paper-1", 0, &tree), HMSM_OK);
    ASSERT_EQ(hmsm_scene_create(&scene), HMSM_OK);
    ASSERT_EQ(hmsm_scene_add_model(scene, tree, "paper-1", nullptr), HMSM_OK);
    hmsm_instance instance;
    ASSERT_EQ(HMSM_INIT(hmsm_instance_init, &instance), HMSM_OK);
    ASSERT_EQ(hmsm_scene_add_instance(scene, &instance), HMSM_OK);
    instance.origin[0] = 9.0;
    instance.yaw = 0.7;
    ASSERT_EQ(hmsm_scene_add_instance(scene, &instance), HMSM_OK);
    hmsm_config config;
    ASSERT_EQ(HMSM_INIT(hmsm_config_init, &config), HMSM_OK);
    config.backend = HMSM_BACKEND_CPU;
    config.wind.profile = HMSM_WIND_CONSTANT;
    config.wind.strength = 6.0;
    ASSERT_EQ(hmsm_simulation_create(scene, &config, &out.c), HMSM_OK) << hmsm_status_message();
    hmsm_scene_destroy(scene);
    hmsm_tree_destroy(tree);
    ASSERT_EQ(hmsm_skin_create(out.c, 0, &out.skin), HMSM_OK) << hmsm_status_message();
}

std::vector<float> read_f32(const hmsm_simulation* sim, int32_t output) {
    size_t count = 0;
    EXPECT_EQ(hmsm_simulation_read_f32(sim, output, nullptr, 0, &count), HMSM_OK);
    std::vector<float> values(count);
    EXPECT_EQ(hmsm_simulation_read_f32(sim, output, values.data(), count, &count), HMSM_OK);
    return values;
}

template <class T, class Read>
std::vector<T> read_skin(Read read, const hmsm_skin* skin, int32_t data) {
    size_t count = 0;
    EXPECT_EQ(read(skin, data, nullptr, 0, &count), HMSM_OK) << hmsm_status_message();
    std::vector<T> values(count);
    EXPECT_EQ(read(skin, data, values.data(), count, &count), HMSM_OK) << hmsm_status_message();
    return values;
}

/// The C++ skin of the same model, from a C++ simulation of the same scene.
SkinTemplate cpp_skin(std::unique_ptr<Simulation>& sim) {
    Scene scene;
    scene.models = {*generate_preset("paper-1", 0)};
    scene.model_names = {"paper-1"};
    scene.instances = {Instance{}};
    SimulationConfig config;
    config.backend = BackendKind::cpu;
    auto created = Simulation::create(scene, config);
    EXPECT_TRUE(created.ok());
    sim = std::move(*created);
    return build_skin(sim->scene().models[0], sim->hierarchy(0), sim->mesh(0), sim->config().model);
}

TEST(CSkin, ReadsGiveBuildSkinsData) {
    Paper1 paper;
    make_paper1(paper);
    ASSERT_NE(paper.skin, nullptr);
    std::unique_ptr<Simulation> sim;
    const SkinTemplate skin = cpp_skin(sim);
    uint64_t vertices = 0, chains = 0;
    ASSERT_EQ(hmsm_skin_sizes(paper.skin, &vertices, &chains), HMSM_OK);
    ASSERT_EQ(vertices, skin.vertices.size());
    ASSERT_EQ(chains, skin.inverse_bind.size());
    ASSERT_EQ(chains, 2345u);

    const auto positions = read_skin<double>(hmsm_skin_read_f64, paper.skin, HMSM_SKIN_BIND_POSITIONS);
    const auto positions32 = read_skin<float>(hmsm_skin_read_f32, paper.skin, HMSM_SKIN_BIND_POSITIONS);
    const auto normals = read_skin<double>(hmsm_skin_read_f64, paper.skin, HMSM_SKIN_BIND_NORMALS);
    const auto joints = read_skin<int32_t>(hmsm_skin_read_i32, paper.skin, HMSM_SKIN_JOINTS);
    const auto weights = read_skin<double>(hmsm_skin_read_f64, paper.skin, HMSM_SKIN_WEIGHTS);
    ASSERT_EQ(positions.size(), 3 * vertices);
    ASSERT_EQ(positions32.size(), 3 * vertices);
    ASSERT_EQ(joints.size(), 2 * vertices);
    for (size_t v = 0; v < vertices; ++v) {
        const SkinVertex& s = skin.vertices[v];
        for (int i = 0; i < 3; ++i) {
            ASSERT_EQ(positions[3 * v + i], s.position[i]) << "vertex " << v;
            ASSERT_EQ(positions32[3 * v + i], static_cast<float>(s.position[i])) << "vertex " << v;
            ASSERT_EQ(normals[3 * v + i], s.normal[i]) << "vertex " << v;
        }
        for (int j = 0; j < 2; ++j) {
            ASSERT_EQ(joints[2 * v + j], s.joints[j]) << "vertex " << v;
            ASSERT_EQ(weights[2 * v + j], s.weights[j]) << "vertex " << v;
        }
    }
    const auto inverse = read_skin<double>(hmsm_skin_read_f64, paper.skin, HMSM_SKIN_INVERSE_BIND);
    const auto bind = read_skin<double>(hmsm_skin_read_f64, paper.skin, HMSM_SKIN_BIND_MATRICES);
    const auto parents = read_skin<int32_t>(hmsm_skin_read_i32, paper.skin, HMSM_SKIN_CHAIN_PARENTS);
    ASSERT_EQ(inverse.size(), 12 * chains);
    ASSERT_EQ(parents.size(), chains);
    for (size_t c = 0; c < chains; ++c) {
        for (size_t k = 0; k < 12; ++k) {
            ASSERT_EQ(inverse[12 * c + k], skin.inverse_bind[c][k]) << "chain " << c;
            ASSERT_EQ(bind[12 * c + k], skin.bind[c][k]) << "chain " << c;
        }
        ASSERT_EQ(parents[c], sim->hierarchy(0).chains[c].parent) << "chain " << c;
    }
    EXPECT_EQ(parents[0], -1);
    // A model's own skin: every joint is driven by its own chain.
    const auto sources = read_skin<int32_t>(hmsm_skin_read_i32, paper.skin, HMSM_SKIN_SOURCE_CHAINS);
    ASSERT_EQ(sources.size(), chains);
    for (size_t c = 0; c < chains; ++c) ASSERT_EQ(sources[c], int32_t(c)) << "chain " << c;
}

TEST(CSkin, BadArgumentsFailAndWriteNothing) {
    Paper1 paper;
    make_paper1(paper);
    ASSERT_NE(paper.skin, nullptr);
    hmsm_skin* none = nullptr;
    EXPECT_EQ(hmsm_skin_create(paper.c, 1, &none), HMSM_INVALID_ARGUMENT);
    EXPECT_NE(std::string(hmsm_status_message()).find("model 1"), std::string::npos);
    EXPECT_EQ(none, nullptr);
    EXPECT_EQ(hmsm_skin_create(nullptr, 0, &none), HMSM_INVALID_ARGUMENT);
    EXPECT_EQ(hmsm_skin_create(paper.c, 0, nullptr), HMSM_INVALID_ARGUMENT);
    uint64_t vertices = 7, chains = 7;
    EXPECT_EQ(hmsm_skin_sizes(nullptr, &vertices, &chains), HMSM_INVALID_ARGUMENT);
    EXPECT_EQ(hmsm_skin_sizes(paper.skin, nullptr, &chains), HMSM_INVALID_ARGUMENT);
    EXPECT_EQ(vertices, 7u);

    std::vector<float> small(12, 42.0f);
    size_t count = 0;
    EXPECT_EQ(hmsm_skin_read_f32(paper.skin, HMSM_SKIN_BIND_POSITIONS, small.data(), small.size(), &count),
              HMSM_INVALID_ARGUMENT);
    EXPECT_GT(count, small.size());  // the size needed is still reported
    EXPECT_EQ(small, std::vector<float>(12, 42.0f));
    EXPECT_EQ(hmsm_skin_read_f32(paper.skin, HMSM_SKIN_JOINTS, small.data(), small.size(), &count),
              HMSM_INVALID_ARGUMENT);
    EXPECT_NE(std::string(hmsm_status_message()).find("hmsm_skin_read_i32"), std::string::npos);
    int32_t ints[4] = {5, 5, 5, 5};
    EXPECT_EQ(hmsm_skin_read_i32(paper.skin, HMSM_SKIN_WEIGHTS, ints, 4, &count), HMSM_INVALID_ARGUMENT);
    EXPECT_EQ(hmsm_skin_read_i32(paper.skin, HMSM_SKIN_DATA_COUNT, ints, 4, &count), HMSM_INVALID_ARGUMENT);
    EXPECT_EQ(hmsm_skin_read_i32(paper.skin, -1, ints, 4, &count), HMSM_INVALID_ARGUMENT);
    EXPECT_EQ(hmsm_skin_read_i32(nullptr, HMSM_SKIN_JOINTS, ints, 4, &count), HMSM_INVALID_ARGUMENT);
    EXPECT_EQ(hmsm_skin_read_i32(paper.skin, HMSM_SKIN_JOINTS, ints, 4, nullptr), HMSM_INVALID_ARGUMENT);
    EXPECT_EQ(ints[0], 5);

    // Skinning: sizes, NULLs, a short palette, a non-finite joint matrix.
    std::vector<float> joints = read_f32(paper.c, HMSM_OUTPUT_JOINT_MATRICES);
    size_t needed = 0;
    ASSERT_EQ(hmsm_skin_vertices(paper.skin, nullptr, 0, nullptr, nullptr, 0, &needed, 1), HMSM_OK);
    std::vector<float> positions(needed, 42.0f), normals(needed, 42.0f);
    const std::vector<float> untouched(needed, 42.0f);
    EXPECT_EQ(hmsm_skin_vertices(paper.skin, joints.data(), joints.size(), positions.data(), normals.data(),
                                 needed - 1, &count, 1),
              HMSM_INVALID_ARGUMENT);
    EXPECT_EQ(hmsm_skin_vertices(paper.skin, nullptr, joints.size(), positions.data(), nullptr, needed, &count, 1),
              HMSM_INVALID_ARGUMENT);
    EXPECT_EQ(hmsm_skin_vertices(paper.skin, joints.data(), 12 * 2345 - 1, positions.data(), nullptr, needed,
                                 &count, 1),
              HMSM_INVALID_ARGUMENT);
    EXPECT_NE(std::string(hmsm_status_message()).find("joint_values"), std::string::npos);
    EXPECT_EQ(hmsm_skin_vertices(nullptr, joints.data(), joints.size(), positions.data(), nullptr, needed,
                                 &count, 1),
              HMSM_INVALID_ARGUMENT);
    EXPECT_EQ(hmsm_skin_vertices(paper.skin, joints.data(), joints.size(), positions.data(), nullptr, needed,
                                 nullptr, 1),
              HMSM_INVALID_ARGUMENT);
    joints[12 * 100 + 5] = NAN;
    EXPECT_EQ(hmsm_skin_vertices(paper.skin, joints.data(), joints.size(), positions.data(), normals.data(),
                                 needed, &count, 0),
              HMSM_INVALID_ARGUMENT);
    EXPECT_NE(std::string(hmsm_status_message()).find("chain 100"), std::string::npos);
    EXPECT_EQ(positions, untouched);
    EXPECT_EQ(normals, untouched);
}

/// |a - b| over xyz triples, the largest.
double largest_distance(const std::vector<float>& a, const std::vector<float>& b, size_t offset = 0) {
    double largest = 0.0;
    for (size_t v = 0; v + 2 < a.size(); v += 3) {
        const double dx = a[v] - b[offset + v], dy = a[v + 1] - b[offset + v + 1], dz = a[v + 2] - b[offset + v + 2];
        largest = std::max(largest, std::sqrt(dx * dx + dy * dy + dz * dz));
    }
    return largest;
}

/// Pass 7 and the skin are the same formula (docs/model.md 3.10), so skinning the bind mesh
/// with the simulation's joint matrices gives its vertices up to float rounding: the joint
/// matrices are floats (relative 6e-8 of coordinates up to the tree's height, through two
/// affine products), and pass 7 accumulates in float along each chain, which the existing skin
/// tests bound by 1e-5 of the height. At rest the skin reproduces the bind pose itself.
TEST(CSkin, SkinningReproducesTheSimulationsVertices) {
    Paper1 paper;
    make_paper1(paper);
    ASSERT_NE(paper.skin, nullptr);
    uint64_t vertices = 0, chains = 0;
    ASSERT_EQ(hmsm_skin_sizes(paper.skin, &vertices, &chains), HMSM_OK);
    const double height = tree_height(*generate_preset("paper-1", 0));
    const double tolerance = 1e-5 * height;

    // Rest: the bind matrices as the palette give the bind positions (float rounding only).
    const auto bind = read_skin<float>(hmsm_skin_read_f32, paper.skin, HMSM_SKIN_BIND_MATRICES);
    const auto bind_positions = read_skin<float>(hmsm_skin_read_f32, paper.skin, HMSM_SKIN_BIND_POSITIONS);
    std::vector<float> positions(3 * vertices), normals(3 * vertices);
    size_t count = 0;
    ASSERT_EQ(hmsm_skin_vertices(paper.skin, bind.data(), bind.size(), positions.data(), nullptr,
                                 positions.size(), &count, 1),
              HMSM_OK);
    EXPECT_LT(largest_distance(positions, bind_positions), 1e-6 * height);
    const std::vector<float> rest = read_f32(paper.c, HMSM_OUTPUT_VERTEX_POSITIONS);
    const std::vector<float> rest_joints = read_f32(paper.c, HMSM_OUTPUT_JOINT_MATRICES);
    ASSERT_EQ(hmsm_skin_vertices(paper.skin, rest_joints.data(), rest_joints.size(), positions.data(), nullptr,
                                 positions.size(), &count, 1),
              HMSM_OK);
    EXPECT_LT(largest_distance(positions, rest), tolerance);

    // Moved: 40 steps of wind; both instances, the second from its chain base on.
    ASSERT_EQ(hmsm_simulation_step(paper.c, 40), HMSM_OK);
    const std::vector<float> joints = read_f32(paper.c, HMSM_OUTPUT_JOINT_MATRICES);
    const std::vector<float> simulated = read_f32(paper.c, HMSM_OUTPUT_VERTEX_POSITIONS);
    const std::vector<float> simulated_normals = read_f32(paper.c, HMSM_OUTPUT_VERTEX_NORMALS);
    ASSERT_GT(largest_distance(simulated, rest), 1e3 * tolerance) << "the wind must move the tree";
    for (uint64_t instance = 0; instance < 2; ++instance) {
        SCOPED_TRACE(instance);
        const size_t chain_base = instance * chains;
        ASSERT_EQ(hmsm_skin_vertices(paper.skin, joints.data() + 12 * chain_base, joints.size() - 12 * chain_base,
                                     positions.data(), normals.data(), positions.size(), &count, 1),
                  HMSM_OK);
        EXPECT_LT(largest_distance(positions, simulated, 3 * instance * vertices), tolerance);
        EXPECT_LT(largest_distance(normals, simulated_normals, 3 * instance * vertices), 1e-4);
        // Threaded: the same arithmetic per vertex, so the same bits.
        std::vector<float> threaded(positions.size()), threaded_normals(normals.size());
        ASSERT_EQ(hmsm_skin_vertices(paper.skin, joints.data() + 12 * chain_base, joints.size() - 12 * chain_base,
                                     threaded.data(), threaded_normals.data(), threaded.size(), &count, 0),
                  HMSM_OK);
        EXPECT_EQ(threaded, positions);
        EXPECT_EQ(threaded_normals, normals);
    }
}

/// The C++ entry point directly: a straightforward double reference of docs/skinning.md's
/// formula agrees, and short spans are refused.
TEST(CSkin, CppSkinVerticesMatchesTheFormula) {
    std::unique_ptr<Simulation> sim;
    const SkinTemplate skin = cpp_skin(sim);
    ASSERT_TRUE(sim->step(30).ok());
    std::vector<float> joints;
    ASSERT_TRUE(sim->read(Output::joint_matrices, joints).ok());
    std::vector<float> positions(3 * skin.vertices.size());
    ASSERT_TRUE(skin_vertices(skin, joints, positions, {}, 3).ok());
    double largest = 0.0;
    for (size_t v = 0; v < skin.vertices.size(); ++v) {
        const SkinVertex& s = skin.vertices[v];
        double p[3] = {0, 0, 0};
        for (int j = 0; j < 2; ++j) {
            if (s.joints[j] < 0) continue;
            const float* m = &joints[12 * size_t(s.joints[j])];
            const auto& inv = skin.inverse_bind[size_t(s.joints[j])];
            double local[3];
            for (int i = 0; i < 3; ++i)
                local[i] = inv[4 * i] * s.position.x + inv[4 * i + 1] * s.position.y + inv[4 * i + 2] * s.position.z +
                           inv[4 * i + 3];
            for (int i = 0; i < 3; ++i)
                p[i] += s.weights[j] * (m[4 * i] * local[0] + m[4 * i + 1] * local[1] + m[4 * i + 2] * local[2] +
                                        m[4 * i + 3]);
        }
        for (int i = 0; i < 3; ++i) largest = std::max(largest, std::abs(p[i] - positions[3 * v + i]));
    }
    EXPECT_LT(largest, 1e-6 * tree_height(sim->scene().models[0]));
    std::vector<float> short_positions(positions.size() - 1);
    EXPECT_EQ(skin_vertices(skin, joints, short_positions).code(), ErrorCode::invalid_argument);
    EXPECT_EQ(skin_vertices(skin, std::span<const float>(joints).first(11), positions).code(),
              ErrorCode::invalid_argument);
}

}  // namespace

/// A level's skin through the C ABI (hmsm_skin_create_level): at most max_joints joints, its
/// data is build_skin()'s for that level, and with the model's joint matrices of its source
/// chains it draws the full rest mesh. Bad options are refused and leave the handle unset.
TEST(CSkin, LevelSkinHasItsJointBudgetAndDrawsTheRestMesh) {
    Paper1 paper;
    make_paper1(paper);
    hmsm_level_options options;
    ASSERT_EQ(HMSM_INIT(hmsm_level_options_init, &options), HMSM_OK);
    EXPECT_EQ(options.max_joints, 256);
    options.max_joints = 64;
    hmsm_skin* level = nullptr;
    ASSERT_EQ(hmsm_skin_create_level(paper.c, 0, &options, &level), HMSM_OK) << hmsm_status_message();
    uint64_t vertices = 0, chains = 0, full_vertices = 0, full_chains = 0;
    ASSERT_EQ(hmsm_skin_sizes(level, &vertices, &chains), HMSM_OK);
    ASSERT_EQ(hmsm_skin_sizes(paper.skin, &full_vertices, &full_chains), HMSM_OK);
    EXPECT_EQ(chains, 64u);
    EXPECT_EQ(vertices, full_vertices);

    std::unique_ptr<Simulation> sim;
    cpp_skin(sim);
    auto built = build_level(sim->scene().models[0], sim->hierarchy(0), sim->config().parameters, 64);
    ASSERT_TRUE(built.ok());
    const auto sources = read_skin<int32_t>(hmsm_skin_read_i32, level, HMSM_SKIN_SOURCE_CHAINS);
    EXPECT_EQ(sources, built->source_chain);
    const auto joints = read_skin<int32_t>(hmsm_skin_read_i32, level, HMSM_SKIN_JOINTS);
    const auto weights = read_skin<double>(hmsm_skin_read_f64, level, HMSM_SKIN_WEIGHTS);
    for (size_t v = 0; v < vertices; ++v) {
        ASSERT_NEAR(weights[2 * v] + weights[2 * v + 1], 1.0, 1e-12) << "vertex " << v;
        for (int j = 0; j < 2; ++j) ASSERT_LT(joints[2 * v + size_t(j)], 64) << "vertex " << v;
    }

    const std::vector<float> rest = read_f32(paper.c, HMSM_OUTPUT_VERTEX_POSITIONS);
    const std::vector<float> palette = read_f32(paper.c, HMSM_OUTPUT_JOINT_MATRICES);
    std::vector<float> gathered;
    for (int32_t source : sources)
        gathered.insert(gathered.end(), palette.begin() + 12 * source, palette.begin() + 12 * source + 12);
    std::vector<float> positions(3 * vertices);
    size_t count = 0;
    ASSERT_EQ(hmsm_skin_vertices(level, gathered.data(), gathered.size(), positions.data(), nullptr,
                                 positions.size(), &count, 1),
              HMSM_OK);
    EXPECT_LT(largest_distance(positions, rest), 1e-5 * tree_height(*generate_preset("paper-1", 0)));
    hmsm_skin_destroy(level);

    hmsm_skin* untouched = nullptr;
    options.max_joints = 0;
    EXPECT_EQ(hmsm_skin_create_level(paper.c, 0, &options, &untouched), HMSM_INVALID_ARGUMENT);
    EXPECT_NE(std::string(hmsm_status_message()).find("trunk-only"), std::string::npos) << hmsm_status_message();
    EXPECT_EQ(hmsm_skin_create_level(paper.c, 0, nullptr, &untouched), HMSM_INVALID_ARGUMENT);
    EXPECT_EQ(hmsm_skin_create_level(paper.c, 3, &options, &untouched), HMSM_INVALID_ARGUMENT);
    options.max_joints = 16;
    options.struct_size = 0;
    EXPECT_EQ(hmsm_skin_create_level(paper.c, 0, &options, &untouched), HMSM_INVALID_ARGUMENT);
    EXPECT_NE(std::string(hmsm_status_message()).find("hmsm_level_options"), std::string::npos);
    EXPECT_EQ(untouched, nullptr);
}
