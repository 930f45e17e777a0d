// Live control and streaming under the threading contract of include/hmsm/simulation.h, for
// ThreadSanitizer (tools/tsan.sh): simulations changed live (instances added, removed and reset,
// wind and force fields replaced) in several threads at once, and one simulation handed between
// threads that take turns under a mutex (one thread at a time), on cpu and cpu-parallel.
#include <hmsm/hmsm.h>

#include <gtest/gtest.h>

#include <cmath>
#include <mutex>
#include <thread>
#include <vector>

namespace {

hmsm::Scene live_scene() {
    hmsm::TreeModel tree;
    tree.nodes = {{-1, {0, 0, 0}, 0.2}, {0, {0, 2, 0}, 0.15}, {1, {0.3, 4, 0}, 0.1},
                  {1, {-0.8, 3, 0.2}, 0.05}, {3, {-1.2, 3.6, 0.3}, 0.03}};
    hmsm::Scene scene = hmsm::single_tree_scene(tree);
    for (int i = 1; i < 4; ++i) scene.instances.push_back({0, {6.0 * i, 0, 0}, 0.3 * i});
    return scene;
}

std::unique_ptr<hmsm::Simulation> create(hmsm::BackendKind backend) {
    hmsm::SimulationConfig config;
    config.backend = backend;
    config.cpu_threads = 3;
    config.wind.profile = hmsm::WindProfile::y2;
    auto sim = hmsm::Simulation::create(live_scene(), config);
    EXPECT_TRUE(sim.ok()) << sim.status().message();
    return sim.ok() ? std::move(sim).value() : nullptr;
}

/// Round `round` of a live session: stream an instance in and one out, change the wind and the
/// fields, reset one instance, step. The same rounds give the same state on one backend.
hmsm::Status live_round(hmsm::Simulation& sim, int round) {
    hmsm::Instance added;
    added.origin = {3.0 * round, 0.0, 5.0};
    added.yaw = 0.1 * round;
    HMSM_TRY(sim.add_instances({&added, 1}));
    const uint64_t removed = uint64_t(round) % sim.instance_count();
    HMSM_TRY(sim.remove_instances({&removed, 1}));
    hmsm::Wind wind = sim.wind();
    wind.strength = 1.0 + 0.5 * (round % 4);
    HMSM_TRY(sim.set_wind(wind));
    hmsm::ForceField field;
    field.kind = hmsm::ForceField::Kind::radial;
    field.center = {3.0 * (round % 3), 1.0, 0.0};
    field.radius = 4.0;
    field.radial = round % 2 ? 20.0 : 0.0;
    HMSM_TRY(sim.set_force_fields({&field, 1}));
    HMSM_TRY(sim.set_instance_wind_scale(0, 0.5 + 0.1 * (round % 5)));
    const uint32_t reset = uint32_t(round * 7) % uint32_t(sim.instance_count());
    HMSM_TRY(sim.reset_instances({&reset, 1}));
    return sim.step(3);
}

std::vector<float> nodes_after_rounds(hmsm::Simulation& sim, int rounds, hmsm::Status& status) {
    std::vector<float> nodes;
    for (int r = 0; r < rounds && status; ++r) status = live_round(sim, r);
    if (status) status = sim.read(hmsm::Output::node_positions, nodes);
    return nodes;
}

class Threading : public ::testing::TestWithParam<hmsm::BackendKind> {};

TEST_P(Threading, LiveControlOfDistinctSimulationsRunsConcurrently) {
    auto reference_sim = create(GetParam());
    ASSERT_TRUE(reference_sim);
    hmsm::Status reference_status;
    const std::vector<float> reference = nodes_after_rounds(*reference_sim, 12, reference_status);
    ASSERT_TRUE(reference_status) << reference_status.message();
    std::vector<std::vector<float>> results(3);
    std::vector<hmsm::Status> statuses(3);
    std::vector<std::thread> threads;
    for (size_t t = 0; t < results.size(); ++t)
        threads.emplace_back([&, t] {
            auto sim = create(GetParam());
            if (sim) results[t] = nodes_after_rounds(*sim, 12, statuses[t]);
        });
    for (std::thread& t : threads) t.join();
    for (size_t t = 0; t < results.size(); ++t) {
        EXPECT_TRUE(statuses[t]) << statuses[t].message();
        EXPECT_EQ(results[t], reference) << "thread " << t;
    }
}

TEST_P(Threading, OneSimulationChangedLiveByThreadsInTurn) {
    auto sim = create(GetParam());
    ASSERT_TRUE(sim);
    std::mutex turn;  // one thread at a time, as the contract asks
    std::vector<hmsm::Status> statuses(3);
    std::vector<std::thread> threads;
    threads.emplace_back([&] {  // streaming: instances in and out
        for (int r = 0; r < 10 && statuses[0]; ++r) {
            std::lock_guard lock(turn);
            hmsm::Instance added;
            added.origin = {2.0 * r, 0.0, -4.0};
            statuses[0] = sim->add_instances({&added, 1});
            const uint64_t first = 0;
            if (statuses[0] && sim->instance_count() > 3) statuses[0] = sim->remove_instances({&first, 1});
        }
    });
    threads.emplace_back([&] {  // the weather: wind and fields
        for (int r = 0; r < 10 && statuses[1]; ++r) {
            std::lock_guard lock(turn);
            hmsm::Wind wind = sim->wind();
            wind.strength = 2.0 + r;
            statuses[1] = sim->set_wind(wind);
            hmsm::ForceField field;
            field.center = {0.0, 1.0, 1.0 * r};
            field.directional = {0.0, 0.0, 5.0};
            if (statuses[1]) statuses[1] = sim->set_force_fields({&field, 1});
        }
    });
    threads.emplace_back([&] {  // the game loop: recover an instance, step, read
        for (int r = 0; r < 10 && statuses[2]; ++r) {
            std::lock_guard lock(turn);
            const uint32_t last = uint32_t(sim->instance_count() - 1);
            statuses[2] = sim->reset_instances({&last, 1});
            if (statuses[2]) statuses[2] = sim->step(2);
            std::vector<float> joints;
            if (statuses[2]) statuses[2] = sim->read(hmsm::Output::joint_matrices, joints);
            for (float v : joints)
                if (!std::isfinite(v)) statuses[2] = hmsm::Status{hmsm::ErrorCode::internal, "not finite"};
        }
    });
    for (std::thread& t : threads) t.join();
    for (const hmsm::Status& s : statuses) EXPECT_TRUE(s) << s.message();
}

INSTANTIATE_TEST_SUITE_P(Live, Threading,
                         ::testing::Values(hmsm::BackendKind::cpu, hmsm::BackendKind::cpu_parallel),
                         [](const auto& info) { return info.param == hmsm::BackendKind::cpu ? "cpu" : "cpu_parallel"; });

}  // namespace
