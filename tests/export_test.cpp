// hmsm export --gltf (docs/model.md 3.10 and 5): the GLB is read back with tinygltf and its skin is
// evaluated here, independently of the exporter — joint world matrices from the node hierarchy
// and the clip's keys, times the inverse bind matrices, blended by the weights — and compared
// with hmsm's own vertices after the same number of steps. The Khronos validator checks the file.
#include "cli_fixture.h"
#include "test_trees.h"

#include <tiny_gltf.h>

#include <glm/gtc/quaternion.hpp>
#include <glm/mat4x4.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

using namespace hmsm;
namespace fs = std::filesystem;

namespace {

class Export : public test::CliFixture {};

template <class T>
std::vector<T> read_accessor(const tinygltf::Model& m, int index, int components, int component_type) {
    const tinygltf::Accessor& a = m.accessors.at(size_t(index));
    EXPECT_EQ(a.componentType, component_type);
    const tinygltf::BufferView& v = m.bufferViews.at(size_t(a.bufferView));
    const size_t stride = v.byteStride ? v.byteStride : sizeof(T) * size_t(components);
    const unsigned char* base = m.buffers.at(size_t(v.buffer)).data.data() + v.byteOffset + a.byteOffset;
    std::vector<T> out(a.count * size_t(components));
    for (size_t i = 0; i < a.count; ++i) std::memcpy(&out[i * components], base + i * stride, sizeof(T) * components);
    return out;
}

tinygltf::Model load_glb(const std::string& file) {
    tinygltf::Model model;
    tinygltf::TinyGLTF loader;
    std::string err, warn;
    EXPECT_TRUE(loader.LoadBinaryFromFile(&model, &err, &warn, file)) << err;
    EXPECT_TRUE(err.empty()) << err;
    return model;
}

/// What the exporter was asked for, to rebuild hmsm's own simulation in the test.
struct Case {
    TreeModel tree;
    SimulationConfig config;
    glm::dvec3 origin{0.0};
    double yaw = 0.0;
    double seconds = 0.0, fps = 0.0;
};

/// Skinned vertices of the GLB at key frame k, in primitive order (bark, then leaves).
std::vector<glm::dvec3> skinned_vertices(const tinygltf::Model& m, size_t k, std::vector<glm::dvec3>* normals) {
    // Node rotations at frame k: the channel's key k where animated, else the node's own.
    const tinygltf::Animation& anim = m.animations.at(0);
    std::map<int, glm::dquat> rotation;
    for (const auto& ch : anim.channels) {
        const auto& s = anim.samplers.at(size_t(ch.sampler));
        auto keys = read_accessor<float>(m, s.output, 4, TINYGLTF_COMPONENT_TYPE_FLOAT);
        rotation[ch.target_node] = glm::dquat(keys[4 * k + 3], keys[4 * k], keys[4 * k + 1], keys[4 * k + 2]);
    }
    std::vector<glm::dmat4> world(m.nodes.size(), glm::dmat4(1.0));
    auto local = [&](int n) {
        const tinygltf::Node& node = m.nodes[size_t(n)];
        glm::dmat4 t(1.0);
        if (!node.translation.empty()) t[3] = glm::dvec4(node.translation[0], node.translation[1], node.translation[2], 1.0);
        glm::dquat q(1.0, 0.0, 0.0, 0.0);
        if (!node.rotation.empty()) q = glm::dquat(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]);
        if (rotation.count(n)) q = rotation[n];
        return t * glm::dmat4(glm::mat3_cast(glm::normalize(q)));
    };
    std::function<void(int, const glm::dmat4&)> visit = [&](int n, const glm::dmat4& parent) {
        world[size_t(n)] = parent * local(n);
        for (int child : m.nodes[size_t(n)].children) visit(child, world[size_t(n)]);
    };
    for (int root : m.scenes.at(0).nodes) visit(root, glm::dmat4(1.0));

    const tinygltf::Skin& skin = m.skins.at(0);
    auto ibm = read_accessor<float>(m, skin.inverseBindMatrices, 16, TINYGLTF_COMPONENT_TYPE_FLOAT);
    std::vector<glm::dmat4> joint(skin.joints.size());
    for (size_t j = 0; j < joint.size(); ++j) {
        glm::dmat4 inverse;
        for (int c = 0; c < 4; ++c)
            for (int r = 0; r < 4; ++r) inverse[c][r] = ibm[16 * j + 4 * c + r];
        joint[j] = world[size_t(skin.joints[j])] * inverse;
    }
    std::vector<glm::dvec3> out;
    for (const auto& p : m.meshes.at(0).primitives) {
        auto pos = read_accessor<float>(m, p.attributes.at("POSITION"), 3, TINYGLTF_COMPONENT_TYPE_FLOAT);
        auto nrm = read_accessor<float>(m, p.attributes.at("NORMAL"), 3, TINYGLTF_COMPONENT_TYPE_FLOAT);
        auto jnt = read_accessor<uint16_t>(m, p.attributes.at("JOINTS_0"), 4, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT);
        auto wgt = read_accessor<float>(m, p.attributes.at("WEIGHTS_0"), 4, TINYGLTF_COMPONENT_TYPE_FLOAT);
        for (size_t i = 0; i < pos.size() / 3; ++i) {
            glm::dmat4 blend(0.0);
            for (int s = 0; s < 4; ++s) blend += double(wgt[4 * i + s]) * joint.at(jnt[4 * i + s]);
            out.push_back(glm::dvec3(blend * glm::dvec4(pos[3 * i], pos[3 * i + 1], pos[3 * i + 2], 1.0)));
            if (normals)
                normals->push_back(glm::normalize(glm::dmat3(blend) * glm::dvec3(nrm[3 * i], nrm[3 * i + 1], nrm[3 * i + 2])));
        }
    }
    return out;
}

/// Exports `c` through the CLI, then checks at every key frame that the skin reproduces the
/// vertices (to 1e-5 of tree height) and normals of a cpu64 run of the same number of steps.
void expect_clip_reproduces_simulation(const Case& c, const tinygltf::Model& m) {
    const size_t frames = size_t(std::floor(c.seconds * c.fps + 1e-9)) + 1;
    const auto& anim = m.animations.at(0);
    auto times = read_accessor<float>(m, anim.samplers.at(0).input, 1, TINYGLTF_COMPONENT_TYPE_FLOAT);
    ASSERT_EQ(times.size(), frames);
    for (size_t k = 0; k < frames; ++k) EXPECT_EQ(times[k], float(double(k) / c.fps)) << k;

    auto sim = Simulation::create(single_tree_scene(c.tree, c.origin, c.yaw), c.config);
    ASSERT_TRUE(sim) << sim.status().message();
    double lo = 1e300, hi = -1e300;
    for (const auto& n : c.tree.nodes) lo = std::min(lo, n.position.y), hi = std::max(hi, n.position.y);
    const double tolerance = 1e-5 * (hi - lo);
    std::vector<double> rest;
    ASSERT_TRUE((*sim)->read(Output::vertex_positions, rest).ok());
    uint64_t done = 0;
    double moved = 0.0;
    for (size_t k = 0; k < frames; ++k) {
        const uint64_t steps = uint64_t(std::floor(double(k) / (c.fps * c.config.parameters.dt) + 0.5 + 1e-9));
        ASSERT_TRUE((*sim)->step(uint32_t(steps - done)).ok());
        done = steps;
        std::vector<double> expected, expected_normals;
        ASSERT_TRUE((*sim)->read(Output::vertex_positions, expected).ok());
        ASSERT_TRUE((*sim)->read(Output::vertex_normals, expected_normals).ok());
        std::vector<glm::dvec3> normals;
        auto got = skinned_vertices(m, k, &normals);
        ASSERT_EQ(3 * got.size(), expected.size());
        double error = 0.0, normal_error = 0.0;
        for (size_t i = 0; i < got.size(); ++i)
            for (int a = 0; a < 3; ++a) {
                error = std::max(error, std::abs(got[i][a] - expected[3 * i + a]));
                normal_error = std::max(normal_error, std::abs(normals[i][a] - expected_normals[3 * i + a]));
                moved = std::max(moved, std::abs(expected[3 * i + a] - rest[3 * i + a]));
            }
        EXPECT_LE(error, tolerance) << "frame " << k << " (" << steps << " steps)";
        EXPECT_LE(normal_error, 1e-4) << "frame " << k;
    }
    // The clip must actually move, far beyond the tolerance, for the comparison to mean anything.
    EXPECT_GT(moved, 100.0 * tolerance);
}

TEST_F(Export, Paper1ClipReproducesSimulation) {
    Case c;
    auto tree = generate_preset("paper-1");
    ASSERT_TRUE(tree);
    c.tree = *tree;
    c.config.backend = BackendKind::cpu64;
    c.config.wind.profile = WindProfile::y2;
    c.config.wind.strength = 4.0;
    c.config.wind.frequency = 0.5;
    c.seconds = 1.0;
    c.fps = 6.0;
    auto r = run("export --preset paper-1 --gltf " + path("p1.glb") +
                  " --seconds 1 --fps 6 --wind y2 --wind-strength 4 --wind-frequency 0.5");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    expect_clip_reproduces_simulation(c, load_glb(path("p1.glb")));
}

TEST_F(Export, OddTreeWithOriginYawAndFixWeight) {
    // The model's root away from the origin (the bind pose puts it there), cut chains, an odd
    // ring, origin and yaw in the trunk joint, a fix weight other than 0.5, a frame rate that is
    // not a whole number of steps per frame.
    Case c;
    c.tree = test::small_tree();
    for (TreeNode& n : c.tree.nodes) n.position += Vec3(2.0, 1.0, -3.0);
    ASSERT_TRUE(save_tree(c.tree, path("shifted.json")).ok());
    c.config.backend = BackendKind::cpu64;
    c.config.model.ring_sides = 5;
    c.config.model.fix_weight = 0.3;
    c.config.model.max_chain_segments = 2;
    c.config.parameters.dt = 0.01;
    c.config.wind.profile = WindProfile::y1;
    c.config.wind.strength = 30.0;
    c.config.wind.direction = Vec3(1.0, 0.0, 1.0);
    c.config.wind.frequency = 0.7;
    c.origin = glm::dvec3(1.5, 0.25, -2.0);
    c.yaw = 0.7;
    c.seconds = 1.3;  // frames 0 ... 9 at 7 fps: steps round(k / 0.07)
    c.fps = 7.0;
    auto r = run("export --tree " + path("shifted.json") + " --gltf " + path("small.glb") +
                  " --ring-sides 5 --fix-weight 0.3 --max-chain-segments 2 --dt 0.01 --wind y1 --wind-strength 30"
                  " --wind-dir 1,0,1 --wind-frequency 0.7 --origin 1.5,0.25,-2 --yaw 0.7 --seconds 1.3 --fps 7");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const tinygltf::Model m = load_glb(path("small.glb"));
    expect_clip_reproduces_simulation(c, m);

    // The bind pose is the rest pose of the model as an instance at the origin with yaw 0 (its
    // root at the origin), whatever the instance's placement.
    SimulationConfig at_rest = c.config;
    auto rest = Simulation::create(single_tree_scene(c.tree), at_rest);
    ASSERT_TRUE(rest);
    std::vector<double> expected;
    ASSERT_TRUE((*rest)->read(Output::vertex_positions, expected).ok());
    std::vector<float> bind;
    for (const auto& p : m.meshes.at(0).primitives) {
        auto pos = read_accessor<float>(m, p.attributes.at("POSITION"), 3, TINYGLTF_COMPONENT_TYPE_FLOAT);
        bind.insert(bind.end(), pos.begin(), pos.end());
    }
    ASSERT_EQ(bind.size(), expected.size());
    for (size_t i = 0; i < bind.size(); ++i) EXPECT_NEAR(bind[i], expected[i], 1e-5 * 6.0) << i;
}

TEST_F(Export, FileFollowsTheGltfMapping) {
    for (double beta : {0.0, 0.5, 1.0}) {
        SCOPED_TRACE(beta);
        std::ostringstream args;
        args << "export --tree " << path("small.json") << " --gltf " << path("m.glb")
             << " --seconds 2 --fps 10 --wind constant --wind-strength 40 --fix-weight " << beta;
        auto r = run(args.str());
        ASSERT_EQ(r.exit_code, 0) << r.err;
        tinygltf::Model m = load_glb(path("m.glb"));
        ModelOptions options;
        options.fix_weight = beta;
        TreeModel tree = test::small_tree();
        auto h = build_hierarchy(tree, options);
        ASSERT_TRUE(h);
        const MeshTemplate mesh = build_mesh(tree, *h, options);
        const size_t chains = h->chains.size();

        // One joint node per chain; the joint hierarchy is the chain tree.
        ASSERT_EQ(m.skins.size(), 1u);
        ASSERT_EQ(m.skins[0].joints.size(), chains);
        std::map<int, int> parent_of;
        for (size_t n = 0; n < m.nodes.size(); ++n)
            for (int child : m.nodes[n].children) parent_of[child] = int(n);
        for (size_t c = 0; c < chains; ++c) {
            const int node = m.skins[0].joints[c];
            const int parent = h->chains[c].parent;
            if (parent < 0) EXPECT_EQ(parent_of.count(node), 0u);
            else EXPECT_EQ(parent_of.at(node), m.skins[0].joints[size_t(parent)]);
        }
        // Scene roots: the skinned mesh node (no transform) and the trunk joint.
        int mesh_node = -1;
        for (size_t n = 0; n < m.nodes.size(); ++n)
            if (m.nodes[n].mesh >= 0) mesh_node = int(n);
        ASSERT_GE(mesh_node, 0);
        const auto& mn = m.nodes[size_t(mesh_node)];
        EXPECT_EQ(mn.skin, 0);
        EXPECT_TRUE(mn.translation.empty() && mn.rotation.empty() && mn.scale.empty() && mn.matrix.empty());
        std::vector<int> roots = m.scenes.at(size_t(m.defaultScene)).nodes;
        std::sort(roots.begin(), roots.end());
        std::vector<int> expected_roots{mesh_node, m.skins[0].joints[0]};
        std::sort(expected_roots.begin(), expected_roots.end());
        EXPECT_EQ(roots, expected_roots);

        // Only rotations are animated, LINEAR, one channel per joint; a joint's own rotation is its
        // frame-0 key; consecutive keys never flip sign.
        ASSERT_EQ(m.animations.size(), 1u);
        const auto& anim = m.animations[0];
        EXPECT_EQ(anim.channels.size(), chains);
        for (const auto& ch : anim.channels) {
            EXPECT_EQ(ch.target_path, "rotation");
            const auto& s = anim.samplers.at(size_t(ch.sampler));
            EXPECT_EQ(s.interpolation, "LINEAR");
            auto keys = read_accessor<float>(m, s.output, 4, TINYGLTF_COMPONENT_TYPE_FLOAT);
            ASSERT_EQ(keys.size(), 4u * 21u);
            const auto& own = m.nodes.at(size_t(ch.target_node)).rotation;
            ASSERT_EQ(own.size(), 4u);
            for (int a = 0; a < 4; ++a) EXPECT_EQ(float(own[size_t(a)]), keys[size_t(a)]);
            for (size_t k = 1; k < keys.size() / 4; ++k) {
                double dot = 0.0;
                for (int a = 0; a < 4; ++a) dot += double(keys[4 * k + a]) * keys[4 * (k - 1) + a];
                EXPECT_GE(dot, 0.0) << "node " << ch.target_node << " key " << k;
            }
        }

        // A vertex lists only joints of non-zero weight: 2 on a non-trunk base ring when
        // 0 < beta < 1, else 1; weights sum to 1.
        std::vector<int> listed;
        for (const auto& p : m.meshes.at(0).primitives) {
            auto w = read_accessor<float>(m, p.attributes.at("WEIGHTS_0"), 4, TINYGLTF_COMPONENT_TYPE_FLOAT);
            auto j = read_accessor<uint16_t>(m, p.attributes.at("JOINTS_0"), 4, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT);
            for (size_t i = 0; i < w.size() / 4; ++i) {
                int count = 0;
                for (int s = 0; s < 4; ++s) {
                    if (w[4 * i + s] != 0.0f) ++count;
                    else EXPECT_EQ(j[4 * i + s], 0);
                }
                EXPECT_NEAR(w[4 * i] + w[4 * i + 1] + w[4 * i + 2] + w[4 * i + 3], 1.0, 1e-6);
                listed.push_back(count);
            }
        }
        ASSERT_EQ(listed.size(), mesh.vertices.size());
        for (size_t i = 0; i < listed.size(); ++i) {
            const bool blended = mesh.vertices[i].fix_chain >= 0 && beta > 0.0 && beta < 1.0;
            EXPECT_EQ(listed[i], blended ? 2 : 1) << "vertex " << i;
        }

        // Bark opaque, leaves double-sided, both untextured; the leaf cards are their own primitive.
        ASSERT_EQ(m.meshes[0].primitives.size(), 2u);
        const auto& bark = m.materials.at(size_t(m.meshes[0].primitives[0].material));
        const auto& leaves = m.materials.at(size_t(m.meshes[0].primitives[1].material));
        EXPECT_FALSE(bark.doubleSided);
        EXPECT_TRUE(leaves.doubleSided);
        EXPECT_EQ(bark.alphaMode, "OPAQUE");
        EXPECT_EQ(leaves.alphaMode, "OPAQUE");
        EXPECT_EQ(m.accessors.at(size_t(m.meshes[0].primitives[1].attributes.at("POSITION"))).count,
                  4u * tree.leaves.size());
    }
}

TEST_F(Export, BadArgumentsExitTwoWithoutFile) {
    const std::string out = path("bad.glb");
    const std::string tree = " --tree " + path("small.json");
    for (std::string args : {"--seconds 1 --fps 0", "--seconds 1 --fps -3", "--seconds -1 --fps 10",
                             "--seconds nan --fps 10", "--seconds 1 --fps inf", "--fps 10", "--seconds 1",
                             "--seconds 1 --fps 10 --backend warp", "--seconds 1 --fps 10 --origin 1,2",
                             "--seconds 1 --fps 10 --fix-weight 2", "--seconds 1 --fps 10 --wind gale",
                             "--seconds 1e9 --fps 1e3", "--seconds 1 --fps 10 --dt 0"}) {
        SCOPED_TRACE(args);
        auto r = run("export --gltf " + out + tree + " " + args);
        EXPECT_EQ(r.exit_code, 2) << r.err;
        EXPECT_NE(r.err.find("error"), std::string::npos) << r.err;
        EXPECT_FALSE(fs::exists(out));
        for (const auto& entry : fs::directory_iterator(fs::path(out).parent_path()))
            EXPECT_EQ(entry.path().string().find(".tmp-hmsm"), std::string::npos) << entry.path();
    }
    auto missing = run("export --seconds 1 --fps 10" + tree);  // no --gltf
    EXPECT_EQ(missing.exit_code, 2) << missing.err;
    auto no_tree = run("export --gltf " + out + " --seconds 1 --fps 10 --tree " + path("absent.json"));
    EXPECT_EQ(no_tree.exit_code, 2) << no_tree.err;
    auto no_dir = run("export --gltf " + path("no/such/dir.glb") + tree + " --seconds 1 --fps 10");
    EXPECT_EQ(no_dir.exit_code, 2) << no_dir.err;
    EXPECT_FALSE(fs::exists(out));
}

/// --max-joints N (docs/export.md "Joint budgets"): the skin names at most N joints, every
/// JOINTS_0 entry is one of them, the clip's frame 0 is hmsm's rest mesh, and at every frame the
/// vertices of the chains the level keeps are hmsm's own (the folded ones follow their carriers).
TEST_F(Export, MaxJointsBindsTheMeshToALevelWithinTheBudget) {
    TreeModel tree = *generate_preset("paper-5");
    SimulationConfig config;
    config.backend = BackendKind::cpu64;
    config.wind.profile = WindProfile::constant;
    config.wind.strength = 9.0;
    auto sim = Simulation::create(single_tree_scene(tree), config);
    ASSERT_TRUE(sim) << sim.status().message();
    auto level = build_level(tree, (*sim)->hierarchy(0), config.parameters, 64);
    ASSERT_TRUE(level) << level.status().message();
    const SkinTemplate full_skin = build_skin(tree, (*sim)->hierarchy(0), (*sim)->mesh(0), config.model);
    auto r = run("export --preset paper-5 --gltf " + path("p5.glb") +
                 " --seconds 1 --fps 4 --wind constant --wind-strength 9 --max-joints 64");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.err.find("of 64 joints"), std::string::npos) << r.err;
    const tinygltf::Model m = load_glb(path("p5.glb"));
    ASSERT_EQ(m.skins.at(0).joints.size(), 64u);
    EXPECT_EQ(m.animations.at(0).channels.size(), 64u);
    for (const auto& p : m.meshes.at(0).primitives)
        for (uint16_t joint : read_accessor<uint16_t>(m, p.attributes.at("JOINTS_0"), 4,
                                                      TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT))
            ASSERT_LT(joint, 64);
    const double tolerance = 1e-5 * tree_height(tree);
    uint64_t done = 0;
    size_t compared_moving = 0;
    for (size_t k = 0; k < 5; ++k) {
        const uint64_t steps = uint64_t(std::floor(double(k) / (4.0 * config.parameters.dt) + 0.5 + 1e-9));
        ASSERT_TRUE((*sim)->step(uint32_t(steps - done)).ok());
        done = steps;
        std::vector<double> expected;
        ASSERT_TRUE((*sim)->read(Output::vertex_positions, expected).ok());
        const auto got = skinned_vertices(m, k, nullptr);
        ASSERT_EQ(3 * got.size(), expected.size());
        for (size_t i = 0; i < got.size(); ++i) {
            bool kept = true;  // every joint of the vertex is a chain the level keeps
            for (int32_t joint : full_skin.vertices[i].joints)
                if (joint >= 0) kept = kept && level->source_chain[size_t(level->chain_of[size_t(joint)])] == joint;
            if (k > 0 && !kept) continue;
            compared_moving += k > 0;
            for (int a = 0; a < 3; ++a)
                ASSERT_NEAR(got[i][a], expected[3 * i + size_t(a)], tolerance) << "frame " << k << ", vertex " << i;
        }
    }
    EXPECT_GT(compared_moving, 0u);
}

TEST_F(Export, MaxJointsBelowTheTrunkOnlyLevelIsRefused) {
    for (const char* budget : {"0", "-4"})
        expect_bad_input("export --gltf " + path("bad.glb") + " --tree " + path("small.json") +
                             " --seconds 1 --fps 10 --max-joints " + budget,
                         "trunk-only");
    auto whole = run("export --gltf " + path("whole.glb") + " --tree " + path("small.json") +
                     " --seconds 0.5 --fps 10 --max-joints 100000");
    ASSERT_EQ(whole.exit_code, 0) << whole.err;
    auto h = build_hierarchy(test::small_tree(), {});
    ASSERT_TRUE(h);
    EXPECT_EQ(load_glb(path("whole.glb")).skins.at(0).joints.size(), h->chains.size());
}

// The Khronos glTF validator (tools/gltf/validate.mjs, npm package gltf-validator installed by
// tools/install_deps.sh): zero errors on paper-1 and on a small odd tree.
TEST_F(Export, KhronosValidatorFindsNoError) {
    if (std::system("command -v node > /dev/null 2>&1") != 0) GTEST_SKIP() << "node is not installed";
    const std::string tools = HMSM_GLTF_TOOLS;
    ASSERT_TRUE(fs::exists(tools + "/node_modules/gltf-validator/package.json"))
        << "the glTF validator is missing: run tools/install_deps.sh (npm ci in tools/gltf)";
    ASSERT_TRUE(save_tree(test::rod(), path("rod.json")).ok());  // one chain, no leaves
    struct Export_ { std::string file, args; };
    for (const Export_& e : {Export_{"p1.glb", "--preset paper-1 --seconds 0.5 --fps 12"},
                             Export_{"small.glb", "--tree " + path("small.json") +
                                                      " --seconds 1.3 --fps 7 --ring-sides 3 --fix-weight 0.2 "
                                                      "--origin 4,0,1 --yaw -2 --wind constant --wind-strength 25"},
                             Export_{"still.glb", "--tree " + path("small.json") + " --seconds 0 --fps 30"},
                             Export_{"rod.glb", "--tree " + path("rod.json") + " --seconds 0.5 --fps 24"},
                             Export_{"p1-16.glb", "--preset paper-1 --seconds 0.5 --fps 12 --max-joints 16"}}) {
        SCOPED_TRACE(e.args);
        auto r = run("export --gltf " + path(e.file) + " " + e.args);
        ASSERT_EQ(r.exit_code, 0) << r.err;
        auto v = run_command("node " + tools + "/validate.mjs " + path(e.file));
        EXPECT_EQ(v.exit_code, 0) << v.out << v.err;
        EXPECT_NE(v.out.find(": 0 errors"), std::string::npos) << v.out << v.err;
    }
}

}  // namespace
