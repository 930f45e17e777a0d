// Pins the CPU backends, the cpu64 reference and the serial float path: a hash of quantized
// outputs after 1000 steps. A change here means the model changed; update the table (kGolden)
// only for an intended change of docs/model.md 3 or of the defaults. The float hash also pins
// the float rounding of the cpu backend, so it may differ under another compiler or libm.
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

uint64_t run_and_hash(const Scene& scene, SimulationConfig config, BackendKind backend, int steps) {
    config.backend = backend;
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

/// The golden scenes: a small tree at an origin and yaw in a strong oblique wind, and one
/// paper-5 tree in the default Y1 wind along +x.
enum class GoldenScene { small_tree, paper5 };

Scene golden_scene(GoldenScene which) {
    if (which == GoldenScene::small_tree) return single_tree_scene(test::small_tree(), {1, 0, 2}, 0.4);
    auto tree = generate_preset("paper-5");
    EXPECT_TRUE(tree.ok()) << tree.status().message();
    return tree.ok() ? single_tree_scene(*tree) : Scene{};
}

SimulationConfig golden_config(GoldenScene which) {
    SimulationConfig config;
    if (which == GoldenScene::small_tree) {
        config.wind.strength = 8.0;
        config.wind.direction = {1, 0, 0.3};
    } else {
        config.wind.strength = 4.0;
    }
    return config;
}

/// Every golden hash, after 1000 steps. To renew them after an intended change of the model
/// (docs/model.md 3) or of its defaults, run
///   hmsm_tests --gtest_filter='Golden*'
/// and copy each printed "golden NAME: 0x..." into this table.
struct GoldenCase {
    const char* name;
    GoldenScene scene;
    BackendKind backend;
    uint64_t hash;
};
constexpr GoldenCase kGolden[] = {
    {"small_tree_cpu64", GoldenScene::small_tree, BackendKind::cpu64, 0xb07353ecedc7bb75ull},
    {"paper5_cpu64", GoldenScene::paper5, BackendKind::cpu64, 0xe23d6eb1baf1092bull},
    {"small_tree_cpu", GoldenScene::small_tree, BackendKind::cpu, 0x22a8dcdc4746c3c3ull},
    {"paper5_cpu", GoldenScene::paper5, BackendKind::cpu, 0x41ff1a2a68f11132ull},
};

void PrintTo(const GoldenCase& c, std::ostream* os) { *os << c.name; }

class Golden : public ::testing::TestWithParam<GoldenCase> {};

}  // namespace

TEST_P(Golden, HashAfter1000Steps) {
    const GoldenCase& c = GetParam();
    const uint64_t h = run_and_hash(golden_scene(c.scene), golden_config(c.scene), c.backend, 1000);
    std::printf("golden %s: 0x%016llx\n", c.name, (unsigned long long)h);
    EXPECT_EQ(h, c.hash);
}

INSTANTIATE_TEST_SUITE_P(Scenes, Golden, ::testing::ValuesIn(kGolden),
                         [](const auto& info) { return std::string(info.param.name); });

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
