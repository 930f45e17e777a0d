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
    EXPECT_EQ(h, 0x9fd140ebb69351dfull);
}

TEST(Golden, Paper5Cpu64After1000Steps) {
    auto tree = generate_preset("paper-5");
    ASSERT_TRUE(tree.ok()) << tree.status().message();
    SimulationConfig config;  // default Y1 wind along +x
    config.wind.strength = 4.0;
    uint64_t h = run_and_hash(single_tree_scene(*tree), config, 1000);
    std::printf("paper-5 hash: 0x%016llx\n", (unsigned long long)h);
    EXPECT_EQ(h, 0xa0fc030e406c8482ull);
}
