// Skins through the C ABI (include/hmsm/hmsm_c.h "skins"): the C reads give exactly
// hmsm::build_skin()'s data; bad arguments fail with a message and write nothing.
#include <hmsm/hmsm.h>
#include <hmsm/hmsm_c.h>
#include <hmsm/skin.h>

#include <gtest/gtest.h>

#include <cmath>
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
}

}  // namespace
