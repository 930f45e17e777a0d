// Pins the CPU reference (cpu64): a hash of quantized outputs after 1000 steps. A change here
// means the model changed; update the constant only for an intended change of docs/model.md 3.
#include "test_trees.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

using namespace hmsm;

namespace {

/// FNV-1a over values rounded to 1e-7 (robust to last-bit differences between libms).
uint64_t quantized_hash(const std::vector<double>& values) {
    uint64_t h = 1469598103934665603ull;
    for (double v : values) {
        int64_t q = std::llround(v * 1e7);
        for (int b = 0; b < 8; ++b) {
            h ^= uint64_t(q >> (8 * b)) & 0xffu;
            h *= 1099511628211ull;
        }
    }
    return h;
}

uint64_t run_and_hash(const Scene& scene, SimulationConfig config, int steps) {
    config.backend = BackendKind::cpu64;
    auto sim = Simulation::create(scene, config);
    EXPECT_TRUE(sim.ok()) << sim.status().message();
    if (!sim.ok()) return 0;
    EXPECT_TRUE((*sim)->step(steps).ok());
    std::vector<double> nodes, vertices;
    EXPECT_TRUE((*sim)->read(Output::node_positions, nodes).ok());
    EXPECT_TRUE((*sim)->read(Output::vertex_positions, vertices).ok());
    nodes.insert(nodes.end(), vertices.begin(), vertices.end());
    EXPECT_TRUE(test::all_finite(nodes));
    return quantized_hash(nodes);
}

}  // namespace

TEST(Golden, SmallTreeCpu64After1000Steps) {
    SimulationConfig config;
    config.wind.strength = 8.0;
    config.wind.direction = {1, 0, 0.3};
    uint64_t h = run_and_hash(single_tree_scene(test::small_tree(), {1, 0, 2}, 0.4), config, 1000);
    std::printf("small tree hash: 0x%016llx\n", (unsigned long long)h);
    EXPECT_EQ(h, 0xb07353ecedc7bb75ull);
}

TEST(Golden, Paper5Cpu64After1000Steps) {
    auto tree = generate_preset("paper-5");
    ASSERT_TRUE(tree.ok()) << tree.status().message();
    SimulationConfig config;  // default Y1 wind along +x
    config.wind.strength = 4.0;
    uint64_t h = run_and_hash(single_tree_scene(*tree), config, 1000);
    std::printf("paper-5 hash: 0x%016llx\n", (unsigned long long)h);
    EXPECT_EQ(h, 0xe23d6eb1baf1092bull);
}

TEST(Golden, LiveScheduleCpu64) {
    // The turbulent profile with a front, force fields of both kinds, per-instance wind scale and
    // phase, a frequency change, and instances removed, added and paused (docs/model.md 3.5, 3.9).
    Scene scene = *grid_scene(test::small_tree(), 3, 6.0, 9);
    scene.instances[1].wind_scale = 0.7;
    scene.instances[2].wind_phase = 0.4;
    SimulationConfig config;
    config.backend = BackendKind::cpu64;
    config.wind.profile = WindProfile::turbulent;
    config.wind.strength = 30.0;
    config.wind.turbulence = 0.5;
    config.wind.seed = 42;
    config.wind.front_speed = 4.0;
    config.wind.direction = {1, 0, 0.4};
    auto sim = Simulation::create(scene, config);
    ASSERT_TRUE(sim.ok()) << sim.status().message();
    ASSERT_TRUE((*sim)->step(300).ok());
    ForceField fields[2];
    fields[0].center = {0, 3, 0};
    fields[0].radius = 8.0;
    fields[0].directional = {0, 0, 40};
    fields[1].kind = ForceField::Kind::radial;
    fields[1].center = {-6, 2, 0};
    fields[1].radius = 5.0;
    fields[1].radial = 25.0;
    ASSERT_TRUE((*sim)->set_force_fields(fields).ok());
    ASSERT_TRUE((*sim)->step(300).ok());
    Wind wind = (*sim)->wind();
    wind.profile = WindProfile::y3;
    wind.frequency = 0.25;
    ASSERT_TRUE((*sim)->set_wind(wind).ok());
    const uint64_t gone[] = {0};
    ASSERT_TRUE((*sim)->remove_instances(gone).ok());
    const Instance added[] = {{0, {9, 0, 3}, 0.2, 1.3, 0.1}};
    ASSERT_TRUE((*sim)->add_instances(added).ok());
    ASSERT_TRUE((*sim)->set_instance_active(1, false).ok());
    ASSERT_TRUE((*sim)->step(400).ok());
    std::vector<double> nodes, vertices;
    ASSERT_TRUE((*sim)->read(Output::node_positions, nodes).ok());
    ASSERT_TRUE((*sim)->read(Output::vertex_positions, vertices).ok());
    nodes.insert(nodes.end(), vertices.begin(), vertices.end());
    ASSERT_TRUE(test::all_finite(nodes));
    const uint64_t h = quantized_hash(nodes);
    std::printf("live schedule hash: 0x%016llx\n", (unsigned long long)h);
    EXPECT_EQ(h, 0x8e052d82a6f3e4cbull);
}
