// Determinism: the same inputs give bitwise-identical outputs run after run, on each
// backend this machine has; how a run is cut into step() calls does not matter either.
// (The CPU reference's golden hash, tests/golden_test.cpp, runs in every build of this suite:
// Release in tools/test.sh, Debug + ASan/UBSan in tools/sanitize.sh.)
#include "test_trees.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <sys/wait.h>
#include <unistd.h>

using namespace hmsm;

namespace {

/// Every output of a simulation, as raw bytes in the backend's own precision.
struct Snapshot {
    std::vector<std::vector<float>> as_float;
    std::vector<std::vector<double>> as_double;
};

constexpr Output kOutputs[] = {Output::node_positions, Output::vertex_positions, Output::vertex_normals,
                               Output::chain_rotations, Output::chain_origins, Output::chain_angles};

Snapshot snapshot(const Simulation& sim) {
    Snapshot s;
    for (Output o : kOutputs) {
        s.as_float.emplace_back();
        s.as_double.emplace_back();
        EXPECT_TRUE(sim.read(o, s.as_float.back()).ok());
        EXPECT_TRUE(sim.read(o, s.as_double.back()).ok());
    }
    return s;
}

void expect_identical(const Snapshot& a, const Snapshot& b) {
    for (size_t k = 0; k < std::size(kOutputs); ++k) {
        EXPECT_TRUE(test::same_bits(a.as_float[k], b.as_float[k])) << "output " << k << " (float)";
        EXPECT_TRUE(test::same_bits(a.as_double[k], b.as_double[k])) << "output " << k << " (double)";
        EXPECT_TRUE(test::all_finite(a.as_double[k]));
    }
}

/// A forest of two models with yaws, a travelling front and a gusty profile.
Scene test_scene() {
    Scene scene;
    scene.models = {test::small_tree(), test::deep_tree(5)};
    scene.model_names = {"small", "deep"};
    scene.instances = {{0, {0, 0, 0}, 0.3}, {1, {7, 0, -2}, 1.1}, {0, {-5, 0.5, 4}, 4.0}, {1, {2, 0, 9}, -0.7}};
    return scene;
}

SimulationConfig test_config(BackendKind backend) {
    SimulationConfig config;
    config.backend = backend;
    config.profile_passes = false;
    config.wind.profile = WindProfile::y4;
    config.wind.strength = 12.0;
    config.wind.direction = {1.0, 0.2, 0.6};
    config.wind.frequency = 0.7;
    config.wind.front_speed = 6.0;
    return config;
}

class Determinism : public ::testing::TestWithParam<BackendKind> {};

}  // namespace

TEST_P(Determinism, SameInputsGiveBitwiseIdenticalOutputs) {
    const Scene scene = test_scene();
    const SimulationConfig config = test_config(GetParam());
    std::string skip;
    auto first = test::create_simulation_or_skip(scene, config, config.backend, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(first);
    auto second = test::create_simulation_or_skip(scene, config, config.backend, skip);
    ASSERT_TRUE(second);
    ASSERT_TRUE(first->step(700).ok());
    // The second run takes the same 700 steps in uneven pieces.
    for (uint32_t chunk : {1u, 2u, 97u, 240u, 360u}) ASSERT_TRUE(second->step(chunk).ok());
    ASSERT_EQ(first->steps_done(), second->steps_done());
    expect_identical(snapshot(*first), snapshot(*second));
    // And a third, created after the others ran, agrees too (no hidden shared state).
    auto third = test::create_simulation_or_skip(scene, config, config.backend, skip);
    ASSERT_TRUE(third);
    ASSERT_TRUE(third->step(700).ok());
    expect_identical(snapshot(*first), snapshot(*third));
}

/// Two simulations in `composition` end bit for bit equal after 300 steps, one run as one
/// call and the other in uneven calls (1 + 57 + 242).
void expect_repeatable(BackendKind backend, Composition composition) {
    const Scene scene = test_scene();
    SimulationConfig config = test_config(backend);
    config.composition = composition;
    std::string skip;
    auto first = test::create_simulation_or_skip(scene, config, config.backend, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(first);
    auto second = test::create_simulation_or_skip(scene, config, config.backend, skip);
    ASSERT_TRUE(second);
    ASSERT_TRUE(first->step(300).ok());
    for (uint32_t chunk : {1u, 57u, 242u}) ASSERT_TRUE(second->step(chunk).ok());
    expect_identical(snapshot(*first), snapshot(*second));
}

TEST_P(Determinism, LevelByLevelIsAlsoRepeatable) { expect_repeatable(GetParam(), Composition::level_by_level); }

TEST_P(Determinism, PathWalkIsAlsoRepeatable) { expect_repeatable(GetParam(), Composition::path_walk); }

INSTANTIATE_TEST_SUITE_P(Backends, Determinism,
                         ::testing::Values(BackendKind::cpu, BackendKind::cpu64, BackendKind::cpu_parallel,
                                           BackendKind::vulkan, BackendKind::cuda),
                         test::BackendTestName());

namespace {

std::string slurp(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

}  // namespace

// Through the CLI: two runs write byte-identical node CSVs and vertex dumps.
TEST(DeterminismCli, TwoRunsWriteIdenticalFiles) {
    namespace fs = std::filesystem;
    auto dir = fs::temp_directory_path() / ("hmsm_determinism_cli_" + std::to_string(getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    const std::string tree = (dir / "tree.json").string();
    ASSERT_TRUE(save_tree(test::small_tree(), tree).ok());
    for (const char* backend : {"cpu", "cpu64", "cpu-parallel"}) {
        SCOPED_TRACE(backend);
        for (int run = 0; run < 2; ++run) {
            std::string tag = std::string(backend) + std::to_string(run);
            std::string command = std::string(HMSM_CLI_PATH) + " simulate --tree " + tree + " --backend " + backend +
                                  " --instances 3 --spacing 6 --seed 4 --wind y2 --wind-strength 9 --front-speed 3"
                                  " --steps 500 --dump-nodes " + (dir / (tag + ".csv")).string() +
                                  " --dump-vertices " + (dir / (tag + ".bin")).string() + " 2>/dev/null";
            int status = std::system(command.c_str());
            ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << command;
        }
        std::string b = backend;
        EXPECT_EQ(slurp(dir / (b + "0.csv")), slurp(dir / (b + "1.csv")));
        std::string v0 = slurp(dir / (b + "0.bin")), v1 = slurp(dir / (b + "1.bin"));
        EXPECT_FALSE(v0.empty());
        EXPECT_TRUE(v0 == v1) << "vertex dumps differ";
    }
    fs::remove_all(dir);
}
