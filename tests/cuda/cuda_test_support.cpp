#include "cuda_test_support.h"

#include "model/random.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace hmsm::cuda_test {

TreeModel random_tree(uint64_t seed, int node_count, int leaf_count) {
    detail::Random random(seed);
    TreeModel tree;
    std::vector<glm::dvec3> direction;  // of the segment ending at each node
    tree.nodes.push_back({-1, {0.0, 0.0, 0.0}, 0.3});
    direction.push_back({0.0, 1.0, 0.0});
    // Trunk: six segments of 1.5 m.
    for (int i = 1; i <= 6 && int(tree.nodes.size()) < node_count; ++i) {
        tree.nodes.push_back({i - 1, {0.0, 1.5 * i, 0.05 * i}, 0.3 - 0.03 * i});
        direction.push_back(glm::normalize(glm::dvec3(0.0, 1.5, 0.05)));
    }
    while (int(tree.nodes.size()) < node_count) {
        // Grow from a recent node most of the time (long chains), sometimes branch lower down.
        const int n = int(tree.nodes.size());
        int parent = random.uniform() < 0.7 ? n - 1 - int(random.below(std::min(n, 3)))
                                            : 1 + int(random.below(n - 1));
        const glm::dvec3 jitter(random.normal(), random.normal(), random.normal());
        glm::dvec3 d = glm::normalize(direction[parent] + 0.6 * jitter + glm::dvec3(0.0, 0.3, 0.0));
        const double length = random.uniform(0.2, 0.6);
        const double radius = std::max(0.06, 0.9 * tree.nodes[parent].radius);
        tree.nodes.push_back({parent, tree.nodes[parent].position + length * d, radius});
        direction.push_back(d);
    }
    for (int l = 0; l < leaf_count; ++l) {
        TreeLeaf leaf;
        leaf.node = 1 + int(random.below(tree.nodes.size() - 1));
        leaf.offset = {random.uniform(-0.05, 0.05), random.uniform(0.0, 0.1), random.uniform(-0.05, 0.05)};
        leaf.normal = glm::normalize(glm::dvec3(random.normal(), random.normal(), 2.0));
        leaf.up = {0.0, 1.0, 0.0};
        leaf.size = {random.uniform(0.05, 0.15), random.uniform(0.05, 0.15)};
        tree.leaves.push_back(leaf);
    }
    return tree;
}

Scene forest_scene(uint64_t seed) {
    detail::Random random(seed * 7919 + 1);
    Scene scene;
    scene.models = {random_tree(seed, 157, 23), random_tree(seed + 1, 611, 101)};
    scene.model_names = {"small", "large"};
    for (uint32_t model : {0u, 0u, 1u, 1u, 0u}) {
        Instance instance;
        instance.model = model;
        instance.origin = {random.uniform(-40.0, 40.0), random.uniform(-1.0, 1.0), random.uniform(-40.0, 40.0)};
        instance.yaw = random.uniform(-3.0, 3.0);
        scene.instances.push_back(instance);
    }
    return scene;
}

Scene many_groups_scene(uint64_t seed, uint32_t instances) {
    detail::Random random(seed * 7919 + 3);
    Scene scene;
    scene.models = {random_tree(seed, 157, 23), random_tree(seed + 1, 611, 101)};
    scene.model_names = {"small", "large"};
    scene.lod_budgets = {{9}, {31}};
    for (uint32_t i = 0; i < instances; ++i) {
        Instance instance;
        instance.model = i % 2;
        instance.origin = {random.uniform(-60.0, 60.0), random.uniform(-1.0, 1.0), random.uniform(-60.0, 60.0)};
        instance.yaw = random.uniform(-3.0, 3.0);
        scene.instances.push_back(instance);
    }
    return scene;
}

void alternate_levels(Simulation& sim) {
    std::vector<InstanceId> ids;
    std::vector<uint32_t> levels;
    for (uint64_t i = 0; i < sim.instance_ids().size(); ++i) {
        if ((i / 2) % 2 == 0) continue;
        ids.push_back(sim.instance_ids()[i]);
        levels.push_back(1);
    }
    const Status status = sim.set_instance_lods(ids, levels);
    ASSERT_TRUE(status.ok()) << status.message();
}

void expect_batches_match_single_launches(Simulation& single, Simulation& batched, Simulation& reference) {
    for (Simulation* sim : {&single, &batched, &reference}) {
        alternate_levels(*sim);
        if (::testing::Test::HasFatalFailure()) return;
    }
    const double height = scene_height(reference.scene());
    const uint32_t calls[] = {1, 3, 2, 4, 1};
    for (uint32_t k = 0; k < std::size(calls); ++k) {
        if (k == 3)
            for (Simulation* sim : {&single, &batched, &reference}) ASSERT_TRUE(sim->set_instance_active(4, false).ok());
        for (Simulation* sim : {&single, &batched, &reference}) {
            const Status status = sim->step(calls[k]);
            ASSERT_TRUE(status.ok()) << status.message();
        }
        for (Output output : {Output::node_positions, Output::vertex_positions, Output::vertex_normals,
                              Output::chain_origins, Output::joint_matrices, Output::chain_angles}) {
            std::vector<double> expected, actual, exact;
            ASSERT_TRUE(single.read(output, expected).ok());
            ASSERT_TRUE(batched.read(output, actual).ok());
            ASSERT_EQ(actual, expected) << "output " << int(output) << " after call " << k;
            if (output == Output::joint_matrices || output == Output::chain_angles) continue;
            ASSERT_TRUE(reference.read(output, exact).ok());
            const bool normals = output == Output::vertex_normals;  // as in cuda_device_test.cpp
            EXPECT_LE(max_abs_difference(actual, exact) / (normals ? 1.0 : height), normals ? 1e-3 : 1e-4)
                << "output " << int(output) << " after call " << k;
        }
    }
}

SimulationConfig test_config(BackendKind backend, Composition composition, bool profile) {
    SimulationConfig config;
    config.backend = backend;
    config.composition = composition;
    config.profile_passes = profile;
    config.wind.profile = WindProfile::y1;
    config.wind.direction = {1.0, 0.0, 0.4};
    config.wind.strength = 10.0;
    config.wind.frequency = 0.3;
    config.wind.front_speed = 8.0;
    return config;
}

void run_live_call(Simulation& sim, const Scene& scene, const LiveScript& script, uint32_t k) {
    Wind wind = sim.wind();
    wind.strength *= 1.5;
    ForceField field;
    field.center = {2, 3, 1};
    field.radius = 15.0;
    field.directional = {4, 0, 2};
    if (k == script.wind) ASSERT_TRUE(sim.set_wind(wind).ok());
    if (k == script.field) ASSERT_TRUE(sim.set_force_fields({&field, 1}).ok());
    if (k == script.scale) ASSERT_TRUE(sim.set_instance_wind_scale(1, 0.3).ok());
    if (k == script.pause) ASSERT_TRUE(sim.set_instance_active(1, false).ok());
    if (k == script.resume) ASSERT_TRUE(sim.set_instance_active(1, true).ok());
    if (k == script.add) ASSERT_TRUE(sim.add_instances({&scene.instances[0], 1}).ok());
    field.center.x = double(k);
    if (k > script.moving_from && k < script.moving_to) ASSERT_TRUE(sim.set_force_fields({&field, 1}).ok());
    ASSERT_TRUE(sim.step(k == script.long_call ? script.long_steps : k % 4 == 3 ? 3 : 1).ok());
}

std::string no_cuda_device_reason() {
    auto backend = detail::create_backend(BackendKind::cuda);
    if (backend) return {};
    return backend.status().message();
}

double max_abs_difference(const std::vector<double>& a, const std::vector<double>& b) {
    if (a.size() != b.size()) return std::numeric_limits<double>::infinity();
    double worst = 0.0;
    for (size_t i = 0; i < a.size(); ++i) {
        const double d = std::abs(a[i] - b[i]);
        if (std::isnan(d)) return std::numeric_limits<double>::infinity();
        worst = std::max(worst, d);
    }
    return worst;
}

double scene_height(const Scene& scene) {
    double height = 0.0;
    for (const TreeModel& model : scene.models) height = std::max(height, tree_height(model));
    return height;
}

}  // namespace hmsm::cuda_test
