// The threading contract of include/hmsm/simulation.h, exercised so that ThreadSanitizer
// (tools/tsan.sh) can check it: distinct simulations run concurrently, const calls (read()
// included) on one simulation run concurrently with each other, cpu-parallel's threads hand
// each other their chunks' results within and across steps, Vulkan simulations are created
// and destroyed from several threads at once, update_lod examines instances on the readback
// threads, and the C ABI's last message is per thread. Also
// read()'s own argument check (PublicApi), on the same small scene.
#include <hmsm/hmsm.h>
#include <hmsm/hmsm_c.h>

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <thread>
#include <vector>

namespace {

hmsm::Scene small_scene() {
    hmsm::TreeModel tree;
    tree.nodes = {{-1, {0, 0, 0}, 0.2}, {0, {0, 2, 0}, 0.15}, {1, {0.3, 4, 0}, 0.1},
                  {1, {-0.8, 3, 0.2}, 0.05}, {3, {-1.2, 3.6, 0.3}, 0.03}};
    hmsm::Scene scene = hmsm::single_tree_scene(tree);
    scene.instances.push_back({0, {6, 0, 0}, 0.7});
    return scene;
}

hmsm::SimulationConfig config_for(hmsm::BackendKind backend) {
    hmsm::SimulationConfig config;
    config.backend = backend;
    config.wind.profile = hmsm::WindProfile::y2;
    return config;
}

/// Creates, steps `steps` times and reads node and vertex positions; the error when any fails.
struct Outcome {
    hmsm::Status status;
    std::vector<float> nodes, vertices;
};
Outcome run(hmsm::BackendKind backend, uint32_t steps) {
    Outcome r;
    auto sim = hmsm::Simulation::create(small_scene(), config_for(backend));
    if (!sim) return {sim.status(), {}, {}};
    r.status = (*sim)->step(steps);
    if (r.status) r.status = (*sim)->read(hmsm::Output::node_positions, r.nodes);
    if (r.status) r.status = (*sim)->read(hmsm::Output::vertex_positions, r.vertices);
    return r;
}

bool vulkan_available() {
    auto sim = hmsm::Simulation::create(small_scene(), config_for(hmsm::BackendKind::vulkan));
    return sim.ok();
}

TEST(Threading, DistinctSimulationsStepConcurrently) {
    const Outcome reference = run(hmsm::BackendKind::cpu, 40);
    ASSERT_TRUE(reference.status) << reference.status.message();
    std::vector<Outcome> results(4);
    std::vector<std::thread> threads;
    for (size_t t = 0; t < results.size(); ++t)
        threads.emplace_back([&results, t] { results[t] = run(hmsm::BackendKind::cpu, 40); });
    for (auto& thread : threads) thread.join();
    for (const Outcome& r : results) {
        ASSERT_TRUE(r.status) << r.status.message();
        EXPECT_EQ(r.nodes, reference.nodes);  // the CPU backend is deterministic
        EXPECT_EQ(r.vertices, reference.vertices);
    }
}

/// Reads every output from `threads` threads at once, `rounds` times each, and compares with
/// reads made alone.
void concurrent_reads(const hmsm::Simulation& sim, int threads_count, int rounds) {
    const hmsm::Output outputs[] = {hmsm::Output::node_positions, hmsm::Output::vertex_positions,
                                    hmsm::Output::vertex_normals, hmsm::Output::chain_angles};
    std::vector<std::vector<float>> reference(4);
    for (int i = 0; i < 4; ++i) ASSERT_TRUE(sim.read(outputs[i], reference[i]));
    std::vector<int> mismatches(threads_count, 0);
    std::vector<std::thread> threads;
    for (int t = 0; t < threads_count; ++t)
        threads.emplace_back([&, t] {
            std::vector<float> values;
            std::vector<double> values64;
            for (int round = 0; round < rounds; ++round) {
                const int i = (t + round) % 4;
                if (!sim.read(outputs[i], values) || values != reference[i]) ++mismatches[t];
                if (!sim.read(outputs[i], values64) || values64.size() != reference[i].size())
                    ++mismatches[t];
                if (sim.node_count() != reference[0].size() / 3 || sim.steps_done() != 30)
                    ++mismatches[t];
            }
        });
    for (auto& thread : threads) thread.join();
    for (int t = 0; t < threads_count; ++t) EXPECT_EQ(mismatches[t], 0) << "thread " << t;
}

TEST(Threading, ConcurrentReadsOnOneCpuSimulation) {
    auto sim = hmsm::Simulation::create(small_scene(), config_for(hmsm::BackendKind::cpu));
    ASSERT_TRUE(sim) << sim.status().message();
    ASSERT_TRUE((*sim)->step(30));
    concurrent_reads(**sim, 4, 50);
}

/// Steps a scene on cpu and on cpu-parallel (4 threads, whatever the host has) in the same
/// pieces, every output read in between, and expects bitwise equal positions.
void expect_parallel_equals_serial(const hmsm::Scene& scene, hmsm::Composition composition) {
    hmsm::SimulationConfig config = config_for(hmsm::BackendKind::cpu);
    config.composition = composition;
    auto serial = hmsm::Simulation::create(scene, config);
    ASSERT_TRUE(serial) << serial.status().message();
    config.backend = hmsm::BackendKind::cpu_parallel;
    config.cpu_threads = 4;
    auto parallel = hmsm::Simulation::create(scene, config);
    ASSERT_TRUE(parallel) << parallel.status().message();
    for (uint32_t steps : {1u, 3u, 1u, 6u}) {
        ASSERT_TRUE((*serial)->step(steps));
        ASSERT_TRUE((*parallel)->step(steps));
        for (hmsm::Output o : {hmsm::Output::node_positions, hmsm::Output::vertex_positions}) {
            std::vector<float> a, b;
            ASSERT_TRUE((*serial)->read(o, a));
            ASSERT_TRUE((*parallel)->read(o, b));
            EXPECT_EQ(a, b) << "output " << int(o) << " after " << (*serial)->steps_done() << " steps";
        }
    }
}

TEST(Threading, CpuParallelThreadsShareAStepOnOneTreeAndOnAForest) {
    // One large tree: every pass is split, hierarchical rounds wait for the round before.
    auto tree = hmsm::generate_preset("paper-1");
    ASSERT_TRUE(tree) << tree.status().message();
    expect_parallel_equals_serial(hmsm::single_tree_scene(*tree), hmsm::Composition::pointer_jumping);
    expect_parallel_equals_serial(hmsm::single_tree_scene(*tree), hmsm::Composition::level_by_level);
    // A forest: each thread its own instances.
    auto forest = hmsm::grid_scene(small_scene().models[0], 300, 5.0, 3);
    ASSERT_TRUE(forest) << forest.status().message();
    expect_parallel_equals_serial(*forest, hmsm::Composition::pointer_jumping);
}

TEST(Threading, UpdateLodExaminesManyInstancesOnTheReadbackThreads) {
    // Thousands of instances around a band edge: update_lod examines them in ranges on the
    // readback threads (the first call every instance, later ones those the viewer's travel
    // may have carried across the edge); the levels are the bands' with hysteresis.
    auto forest = hmsm::grid_scene(small_scene().models[0], 3000, 2.0, 3);
    ASSERT_TRUE(forest) << forest.status().message();
    forest->lod_budgets = {{1}};
    auto sim = hmsm::Simulation::create(*forest, config_for(hmsm::BackendKind::cpu));
    ASSERT_TRUE(sim) << sim.status().message();
    hmsm::LodBands bands;
    bands.edges = {30.0};
    bands.hysteresis = 0.1;
    bands.fade_steps = 0;  // switches at once
    ASSERT_TRUE((*sim)->set_lod_bands(bands).ok());
    const std::vector<hmsm::Instance> instances((*sim)->instances().begin(), (*sim)->instances().end());
    const std::vector<hmsm::InstanceId> ids((*sim)->instance_ids().begin(), (*sim)->instance_ids().end());
    std::vector<uint32_t> expected(instances.size(), 0);
    uint64_t switched = 0;
    for (int call = 0; call < 8; ++call) {
        const hmsm::Vec3 viewer{12.0 * call, 0.0, 40.0 - 6.0 * call};
        auto changed = (*sim)->update_lod(viewer);
        ASSERT_TRUE(changed) << changed.status().message();
        switched += *changed;
        for (size_t i = 0; i < instances.size(); ++i) {
            const hmsm::Vec3 d = instances[i].origin - viewer;
            const double distance = std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
            if (expected[i] == 0 && distance > 30.0 * 1.1) expected[i] = 1;
            else if (expected[i] == 1 && distance < 30.0 * 0.9) expected[i] = 0;
            ASSERT_EQ(*(*sim)->instance_lod(ids[i]), expected[i]) << "instance " << i << ", call " << call;
        }
    }
    EXPECT_GT(switched, 3000u) << "too few switches to examine many instances per call";
}

TEST(Threading, ConcurrentReadsOnOneVulkanSimulation) {
    auto sim = hmsm::Simulation::create(small_scene(), config_for(hmsm::BackendKind::vulkan));
    if (!sim && sim.status().code() == hmsm::ErrorCode::no_device)
        GTEST_SKIP() << sim.status().message();
    ASSERT_TRUE(sim) << sim.status().message();
    ASSERT_TRUE((*sim)->step(30));
    concurrent_reads(**sim, 3, 10);
}

TEST(Threading, VulkanSimulationsCreatedFromTwoThreadsAtOnce) {
    if (!vulkan_available()) GTEST_SKIP() << "no Vulkan device";
    const Outcome reference = run(hmsm::BackendKind::cpu, 20);
    std::vector<Outcome> results(2);
    std::vector<std::thread> threads;
    for (size_t t = 0; t < results.size(); ++t)
        threads.emplace_back([&results, t] {
            for (int again = 0; again < 2; ++again) results[t] = run(hmsm::BackendKind::vulkan, 20);
        });
    for (auto& thread : threads) thread.join();
    for (const Outcome& r : results) {
        ASSERT_TRUE(r.status) << r.status.message();
        ASSERT_EQ(r.nodes.size(), reference.nodes.size());
        for (size_t i = 0; i < r.nodes.size(); ++i)
            EXPECT_NEAR(r.nodes[i], reference.nodes[i], 1e-4) << "node scalar " << i;
    }
}

TEST(Threading, CApiLastMessageIsPerThread) {
    std::vector<std::string> seen(2);
    std::thread a([&] {
        for (int i = 0; i < 100; ++i) {
            hmsm_tree* tree = nullptr;
            if (hmsm_tree_preset("no-such-preset", 0, &tree) == HMSM_OK) return;
            seen[0] = hmsm_status_message();
        }
    });
    std::thread b([&] {
        for (int i = 0; i < 100; ++i) {
            if (hmsm_scene_create(nullptr) == HMSM_OK) return;
            seen[1] = hmsm_status_message();
        }
    });
    a.join();
    b.join();
    EXPECT_NE(seen[0].find("no-such-preset"), std::string::npos) << seen[0];
    EXPECT_NE(seen[1].find("hmsm_scene_create"), std::string::npos) << seen[1];
}

}  // namespace

namespace {

TEST(PublicApi, ReadRejectsAnUnknownOutputAndWritesNothing) {
    auto sim = hmsm::Simulation::create(small_scene(), config_for(hmsm::BackendKind::cpu));
    ASSERT_TRUE(sim) << sim.status().message();
    std::vector<float> values{42.0f};
    std::vector<double> values64{42.0};
    const hmsm::Status status = (*sim)->read(static_cast<hmsm::Output>(99), values);
    EXPECT_EQ(status.code(), hmsm::ErrorCode::invalid_argument);
    EXPECT_NE(status.message().find("99"), std::string::npos) << status.message();
    EXPECT_EQ((*sim)->read(static_cast<hmsm::Output>(-1), values64).code(),
              hmsm::ErrorCode::invalid_argument);
    EXPECT_EQ(values, std::vector<float>{42.0f});
    EXPECT_EQ(values64, std::vector<double>{42.0});
}

}  // namespace
