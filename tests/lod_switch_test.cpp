// Levels of detail at run time (docs/driving.md): switches by handle and by distance bands
// carry the state of the chains both levels keep, keep the instance's index and settings, agree
// with cpu64 on every backend, refuse bad input without a change, and do not flip an instance
// near a band edge every frame.
#include "test_trees.h"

#include <hmsm/hmsm_c.h>
#include <hmsm/levels.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace hmsm {
namespace {

using test::first_elements;
using test::instance_slice;

constexpr int32_t kBudgets[] = {6, 3, 1};
/// The outputs compared per instance: its nodes, and its chains' angles.
constexpr Output kNodes = Output::node_positions, kAngles = Output::chain_angles;

Scene lod_forest() {
    Scene scene = *grid_scene(test::small_tree(), 5, 5.0, 11);
    scene.models.push_back(test::deep_tree(4));
    scene.model_names.push_back("deep");
    scene.instances.insert(scene.instances.begin() + 2, Instance{1, {-6, 0, 8}, 0.4});
    scene.instances.push_back({1, {9, 0, -3}, 1.9, 0.7, 0.3});
    scene.instances[4].active = false;
    scene.lod_budgets = {{std::begin(kBudgets), std::end(kBudgets)}, {std::begin(kBudgets), std::end(kBudgets)}};
    return scene;
}

std::vector<double> read_output(const Simulation& sim, Output output) {
    std::vector<double> values;
    const Status read = sim.read(output, values);
    EXPECT_TRUE(read.ok()) << read.message();
    return values;
}

double vertex_jump(const std::vector<double>& a, const std::vector<double>& b) {
    double largest = 0.0;
    for (size_t k = 0; k + 2 < a.size(); k += 3)
        largest = std::max(largest, std::hypot(a[k] - b[k], a[k + 1] - b[k + 1], a[k + 2] - b[k + 2]));
    return largest;
}

class LodSwitch : public ::testing::TestWithParam<BackendKind> {};

// Fine -> coarse: each kept chain takes its angles and rates bit for bit; coarse -> fine: kept
// chains keep theirs, unfolded chains start at 0. The other instances' outputs do not change,
// and the switched instance keeps handle, index and settings.
TEST_P(LodSwitch, SwitchAndReverseCarryKeptChains) {
    std::string skip;
    auto sim = test::create_simulation_or_skip(lod_forest(), test::windy_config(), GetParam(), skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(sim);
    ASSERT_TRUE(sim->step(40).ok());
    const uint64_t index = 2;  // a deep tree
    const InstanceId id = *sim->id_of(index);
    const Instance settings = sim->instances()[index];
    const auto chains_before = first_elements(*sim, kAngles);
    const auto nodes_before = first_elements(*sim, kNodes);
    const auto angles_fine = read_output(*sim, Output::chain_angles);
    const auto rotations_fine = read_output(*sim, Output::chain_rotations);
    const auto nodes_fine = read_output(*sim, Output::node_positions);

    ASSERT_TRUE(sim->set_instance_lod(id, 2).ok());
    EXPECT_EQ(*sim->instance_lod(id), 2u);
    EXPECT_EQ(*sim->index_of(id), index);
    const Instance& now = sim->instances()[index];
    EXPECT_EQ(now.model, *sim->lod_model(1, 2));
    EXPECT_EQ(now.origin, settings.origin);
    EXPECT_EQ(now.yaw, settings.yaw);
    EXPECT_EQ(now.wind_scale, settings.wind_scale);
    EXPECT_EQ(now.active, settings.active);
    const Hierarchy& coarse = sim->hierarchy(now.model);
    const Hierarchy& fine = sim->hierarchy(1);
    ASSERT_LT(coarse.chains.size(), fine.chains.size());
    const auto chains = first_elements(*sim, kAngles);
    const auto angles_coarse = read_output(*sim, Output::chain_angles);
    const auto rotations_coarse = read_output(*sim, Output::chain_rotations);
    // Which fine chain each coarse one keeps.
    auto level = build_level(test::deep_tree(4), fine, sim->config().parameters, kBudgets[1]);
    ASSERT_TRUE(level.ok());
    ASSERT_EQ(level->source_chain.size(), coarse.chains.size());
    const std::vector<int32_t>& source = level->source_chain;
    for (size_t j = 0; j < coarse.chains.size(); ++j) {
        for (int k = 0; k < 4; ++k)
            EXPECT_EQ(angles_coarse[(chains[index] + j) * 4 + k], angles_fine[(chains_before[index] + size_t(source[j])) * 4 + k])
                << "chain " << j << " component " << k;
        for (int k = 0; k < 9; ++k)
            EXPECT_NEAR(rotations_coarse[(chains[index] + j) * 9 + k],
                        rotations_fine[(chains_before[index] + size_t(source[j])) * 9 + k], 1e-6);
    }
    // Every other instance: its outputs as they were (moved behind the switched one).
    const auto nodes_now = read_output(*sim, Output::node_positions);
    const auto nodes_after = first_elements(*sim, kNodes);
    for (size_t i = 0; i < sim->instance_count(); ++i) {
        if (i == index) continue;
        EXPECT_EQ(instance_slice(nodes_now, nodes_after, i, kNodes),
                  instance_slice(nodes_fine, nodes_before, i, kNodes)) << "instance " << i;
        EXPECT_EQ(instance_slice(angles_coarse, chains, i, kAngles),
                  instance_slice(angles_fine, chains_before, i, kAngles)) << "instance " << i;
    }

    ASSERT_TRUE(sim->set_instance_lod(id, 0).ok());
    const auto angles_back = read_output(*sim, Output::chain_angles);
    const auto rotations_back = read_output(*sim, Output::chain_rotations);
    std::vector<char> kept(fine.chains.size(), 0);
    for (int32_t c : source) kept[size_t(c)] = 1;
    for (size_t c = 0; c < fine.chains.size(); ++c)
        for (int k = 0; k < 4; ++k) {
            const double expected = kept[c] ? angles_fine[(chains_before[index] + c) * 4 + k] : 0.0;
            EXPECT_EQ(angles_back[(chains_before[index] + c) * 4 + k], expected) << "chain " << c;
        }
    for (size_t c = 0; c < fine.chains.size(); ++c)
        if (kept[c])
            for (int k = 0; k < 9; ++k)
                EXPECT_NEAR(rotations_back[(chains_before[index] + c) * 9 + k],
                            rotations_fine[(chains_before[index] + c) * 9 + k], 1e-6);
    EXPECT_EQ(read_output(*sim, Output::chain_angles).size(), angles_fine.size());
    ASSERT_TRUE(sim->step(10).ok());
    EXPECT_TRUE(test::all_finite(read_output(*sim, Output::vertex_positions)));
}

// A float backend through batched switches, switches back and distance bands: within the
// agreement suite's tolerance of cpu64 doing the same.
TEST_P(LodSwitch, AgreesWithCpu64ThroughSwitches) {
    if (GetParam() == BackendKind::cpu64) GTEST_SKIP() << "cpu64 is the oracle";
    std::string skip;
    auto sim = test::create_simulation_or_skip(lod_forest(), test::windy_config(), GetParam(), skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    auto oracle = test::create_simulation_or_skip(lod_forest(), test::windy_config(), BackendKind::cpu64, skip);
    ASSERT_TRUE(sim && oracle);
    auto both = [&](auto&& action) {
        ASSERT_TRUE(action(*sim).ok());
        ASSERT_TRUE(action(*oracle).ok());
    };
    const InstanceId ids[] = {InstanceId(0), InstanceId(2), InstanceId(4), InstanceId(6)};
    const uint32_t coarser[] = {1, 3, 2, 3};
    const uint32_t back[] = {0, 1, 0, 2};
    both([](Simulation& s) { return s.step(60); });
    both([&](Simulation& s) { return s.set_instance_lods(ids, coarser); });
    both([](Simulation& s) { return s.step(60); });
    both([&](Simulation& s) { return s.set_instance_lods(ids, back); });
    both([](Simulation& s) { return s.step(60); });
    both([](Simulation& s) { return s.set_lod_bands({{6.0, 9.0, 12.0}, 0.1}); });
    both([](Simulation& s) { return s.update_lod({0.0, 1.0, 0.0}).status(); });
    both([](Simulation& s) { return s.step(60); });
    both([](Simulation& s) { return s.update_lod({20.0, 1.0, 20.0}).status(); });
    both([](Simulation& s) { return s.step(60); });
    for (size_t i = 0; i < sim->instance_count(); ++i) EXPECT_EQ(sim->instances()[i].model, oracle->instances()[i].model);
    for (Output o : {Output::node_positions, Output::vertex_positions}) {
        auto a = read_output(*sim, o), b = read_output(*oracle, o);
        ASSERT_EQ(a.size(), b.size());
        EXPECT_LE(test::max_abs_difference(a, b), 1e-3) << "output " << int(o);
    }
}

// A level finer than the one the model was created on needs more chains than the device holds:
// the scene is uploaded anew, the state still carries, and the backends agree with cpu64.
TEST_P(LodSwitch, FinerThanCreatedGrowsTheScene) {
    std::string skip;
    Scene scene = lod_forest();
    scene.joint_budgets = {0, 2};
    scene.lod_budgets[1] = {64, 1};
    auto sim = test::create_simulation_or_skip(scene, test::windy_config(), GetParam(), skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    auto oracle = test::create_simulation_or_skip(scene, test::windy_config(), BackendKind::cpu64, skip);
    ASSERT_TRUE(sim && oracle);
    const InstanceId ids[] = {InstanceId(2), InstanceId(6)};
    const uint32_t finer[] = {1, 1};
    for (Simulation* s : {sim.get(), oracle.get()}) {
        ASSERT_TRUE(s->step(50).ok());
        const auto chains_before = first_elements(*s, kAngles);
        const auto angles = read_output(*s, Output::chain_angles);
        ASSERT_TRUE(s->set_instance_lods(ids, finer).ok());
        ASSERT_GT(s->chain_count(), chains_before.back());
        const auto chains = first_elements(*s, kAngles);
        const auto after = read_output(*s, Output::chain_angles);
        EXPECT_EQ(instance_slice(after, chains, 0, kAngles), instance_slice(angles, chains_before, 0, kAngles));
        EXPECT_EQ(instance_slice(after, chains, 3, kAngles), instance_slice(angles, chains_before, 3, kAngles));
        for (int k = 0; k < 4; ++k)  // the trunk is kept by every level
            EXPECT_EQ(after[chains[2] * 4 + uint64_t(k)], angles[chains_before[2] * 4 + uint64_t(k)]);
        ASSERT_TRUE(s->step(50).ok());
    }
    auto a = read_output(*sim, Output::node_positions), b = read_output(*oracle, Output::node_positions);
    ASSERT_EQ(a.size(), b.size());
    EXPECT_LE(test::max_abs_difference(a, b), 1e-3);
}

// The largest vertex jump a switch causes, against the tree's own motion in one frame; vertices
// are those of each level's mesh, vertex for vertex the model's.
TEST_P(LodSwitch, VertexJumpAgainstFrameMotion) {
    std::string skip;
    Scene scene = single_tree_scene(test::deep_tree(4));
    scene.lod_budgets = {{std::begin(kBudgets), std::end(kBudgets)}};
    auto sim = test::create_simulation_or_skip(scene, test::windy_config(), GetParam(), skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(sim->step(120).ok());
    for (uint32_t level : {1u, 2u, 3u, 0u}) {
        const auto before = read_output(*sim, Output::vertex_positions);
        ASSERT_TRUE(sim->step(1).ok());
        const auto frame = read_output(*sim, Output::vertex_positions);
        const uint32_t from = *sim->instance_lod(InstanceId(0));
        ASSERT_TRUE(sim->set_instance_lod(InstanceId(0), level).ok());
        const auto after = read_output(*sim, Output::vertex_positions);
        ASSERT_EQ(after.size(), frame.size());
        const double motion = vertex_jump(before, frame), jump = vertex_jump(frame, after);
        std::printf("[ lod jump ] %s level %u -> %u: largest vertex jump %.3g m, frame motion %.3g m\n",
                    to_string(GetParam()), from, level, jump, motion);
        RecordProperty("jump_" + std::to_string(from) + "_" + std::to_string(level), std::to_string(jump));
        EXPECT_GT(motion, 0.0);
        EXPECT_TRUE(std::isfinite(jump));
        ASSERT_TRUE(sim->step(30).ok());
    }
}

// An instance that starts on a level (Instance::level, at create and in add_instances) runs
// bit for bit as one created or added whole and switched there at once, and never runs its
// finer levels; instances() reports the level it runs on.
TEST_P(LodSwitch, StartingOnALevelIsSwitchingThereAtRest) {
    const std::pair<uint32_t, uint32_t> start[] = {{0, 2}, {2, 3}, {5, 1}};  // (instance, level)
    Scene leveled = lod_forest();
    for (auto [i, level] : start) leveled.instances[i].level = level;
    std::string skip;
    auto started = test::create_simulation_or_skip(leveled, test::windy_config(), GetParam(), skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    auto switched = test::create_simulation_or_skip(lod_forest(), test::windy_config(), GetParam(), skip);
    ASSERT_TRUE(started && switched);
    auto switch_to = [&](std::span<const std::pair<uint32_t, uint32_t>> levels) {
        std::vector<InstanceId> ids;
        std::vector<uint32_t> to;
        for (auto [i, level] : levels) {
            ids.push_back(switched->instance_ids()[i]);
            to.push_back(level);
        }
        ASSERT_TRUE(switched->set_instance_lods(ids, to).ok());
    };
    switch_to(start);
    EXPECT_EQ(started->chain_count(), switched->chain_count());
    EXPECT_TRUE(test::same_bits(test::every_output(*started), test::every_output(*switched)));
    ASSERT_TRUE(started->step(7).ok() && switched->step(7).ok());
    // Arrivals: a deep tree on level 2 and a small one on level 3, against arrivals at level 0
    // switched there.
    Instance deep{1, {4.0, 0.0, 7.0}, 0.3}, small{0, {-5.0, 0.0, 2.0}, 1.1};
    deep.level = 2;
    small.level = 3;
    const Instance arrivals[] = {deep, small};
    ASSERT_TRUE(started->add_instances(arrivals).ok());
    Instance whole[] = {deep, small};
    for (Instance& inst : whole) inst.level = 0;
    ASSERT_TRUE(switched->add_instances(whole).ok());
    const uint32_t n = uint32_t(switched->instance_count());
    const std::pair<uint32_t, uint32_t> arrived[] = {{n - 2, 2}, {n - 1, 3}};
    switch_to(arrived);
    ASSERT_EQ(started->chain_count(), switched->chain_count());
    for (uint32_t i = 0; i < n; ++i) {
        EXPECT_EQ(started->instances()[i].model, switched->instances()[i].model) << "instance " << i;
        EXPECT_EQ(started->instances()[i].level, *switched->instance_lod(switched->instance_ids()[i])) << "instance " << i;
    }
    EXPECT_EQ(started->instances()[n - 1].level, 3u);
    ASSERT_TRUE(started->step(9).ok() && switched->step(9).ok());
    EXPECT_TRUE(test::same_bits(test::every_output(*started), test::every_output(*switched)));
}

std::string backend_name(const ::testing::TestParamInfo<BackendKind>& info) {
    std::string name = to_string(info.param);
    std::replace(name.begin(), name.end(), '-', '_');
    return name;
}

INSTANTIATE_TEST_SUITE_P(Backends, LodSwitch,
                         ::testing::Values(BackendKind::cpu64, BackendKind::cpu, BackendKind::cpu_parallel,
                                           BackendKind::vulkan, BackendKind::cuda),
                         backend_name);

std::unique_ptr<Simulation> cpu64_forest() {
    SimulationConfig config = test::windy_config();
    config.backend = BackendKind::cpu64;
    auto sim = Simulation::create(lod_forest(), config);
    EXPECT_TRUE(sim.ok()) << sim.status().message();
    return sim ? std::move(sim).value() : nullptr;
}

// Bad handles and levels are refused naming them, and nothing changes.
TEST(LodSwitchInput, BadHandlesAndLevelsChangeNothing) {
    auto sim = cpu64_forest();
    ASSERT_TRUE(sim);
    ASSERT_TRUE(sim->step(20).ok());
    const uint64_t removed[] = {1};
    ASSERT_TRUE(sim->remove_instances(removed).ok());
    const auto nodes = read_output(*sim, Output::node_positions);
    const std::vector<Instance> instances(sim->instances().begin(), sim->instances().end());
    auto expect_refused = [&](Status status, const std::string& says) {
        EXPECT_FALSE(status.ok());
        EXPECT_NE(status.message().find(says), std::string::npos) << status.message();
        EXPECT_EQ(read_output(*sim, Output::node_positions), nodes);
        ASSERT_EQ(sim->instances().size(), instances.size());
        for (size_t i = 0; i < instances.size(); ++i) EXPECT_EQ(sim->instances()[i].model, instances[i].model);
    };
    expect_refused(sim->set_instance_lod(InstanceId(1), 1), "instance id 1 was removed");
    expect_refused(sim->set_instance_lod(InstanceId(99), 1), "instance id 99 was never given");
    expect_refused(sim->set_instance_lod(InstanceId(0), 4), "level 4 does not exist");
    const InstanceId twice[] = {InstanceId(2), InstanceId(2)};
    const uint32_t levels[] = {1, 2};
    expect_refused(sim->set_instance_lods(twice, levels), "instance id 2 is listed twice");
    const InstanceId one_then_bad[] = {InstanceId(0), InstanceId(3)};
    const uint32_t then_bad[] = {1, 9};
    expect_refused(sim->set_instance_lods(one_then_bad, then_bad), "level 9");
    EXPECT_EQ(*sim->instance_lod(InstanceId(0)), 0u);
    expect_refused(sim->set_instance_lods(twice, std::span<const uint32_t>(levels, 1)), "2 ids but 1 levels");
    expect_refused(sim->set_lod_bands({{5.0, 5.0}, 0.1}), "edge 1");
    expect_refused(sim->set_lod_bands({{5.0}, 1.0}), "hysteresis");
    EXPECT_TRUE(sim->lod_bands().edges.empty());
    // An added instance on a level its model lacks.
    Instance arrival{1, {3.0, 0.0, 3.0}};
    arrival.level = 4;
    const uint64_t count = sim->instance_count();
    expect_refused(sim->add_instances({&arrival, 1}), "added instance 0: level 4 does not exist (model 'deep' has levels 0 to 3");
    EXPECT_EQ(sim->instance_count(), count);
    // A scene instance on one.
    Scene scene = lod_forest();
    scene.instances[3].level = 7;
    SimulationConfig config;
    config.backend = BackendKind::cpu64;
    auto refused = Simulation::create(scene, config);
    ASSERT_FALSE(refused.ok());
    EXPECT_NE(refused.status().message().find("instance 3: level 7 does not exist"), std::string::npos)
        << refused.status().message();
}

TEST(LodSwitchInput, BudgetBelowTrunkOnlyLevelIsRefused) {
    Scene scene = lod_forest();
    scene.lod_budgets[1] = {4, 0};
    SimulationConfig config = test::windy_config();
    config.backend = BackendKind::cpu64;
    auto sim = Simulation::create(scene, config);
    ASSERT_FALSE(sim.ok());
    EXPECT_NE(sim.status().message().find("model 'deep': level 2 joint budget 0: below the trunk-only level"),
              std::string::npos)
        << sim.status().message();
}

// A forest file sets both budgets per model name; a budget below the trunk-only level is
// refused naming the model.
TEST(LodSwitchInput, ForestSetsBudgetsPerModel) {
    const std::string head = R"({"format": "hmsm-forest", "version": 1,
        "models": {"a": "preset:paper-1", "b": "preset:paper-2"},
        "instances": [{"model": "a"}, {"model": "b", "origin": [9, 0, 0]}],)";
    auto scene = parse_forest(head + R"("joint_budgets": {"b": 64}, "lod_budgets": {"a": [32, 4, 1]}})", ".");
    ASSERT_TRUE(scene.ok()) << scene.status().message();
    ASSERT_EQ(scene->lod_budgets.size(), 2u);
    EXPECT_EQ(scene->lod_budgets[0], (std::vector<int32_t>{32, 4, 1}));
    EXPECT_TRUE(scene->lod_budgets[1].empty());
    EXPECT_EQ(scene->joint_budgets, (std::vector<int32_t>{0, 64}));
    auto bad = parse_forest(head + R"("lod_budgets": {"b": [8, 0]}})", ".");
    ASSERT_FALSE(bad.ok());
    EXPECT_NE(bad.status().message().find("lod_budgets"), std::string::npos) << bad.status().message();
    EXPECT_NE(bad.status().message().find("trunk-only"), std::string::npos) << bad.status().message();
    EXPECT_FALSE(parse_forest(head + R"("lod_budgets": {"c": [8]}})", ".").ok());
}

// A viewer oscillating about a band edge by less than the hysteresis never switches; crossing
// by more switches once, and coming back needs the same margin on the other side.
TEST(LodSwitchBands, HysteresisKeepsAnOscillatingViewerFromFlipping) {
    Scene scene = single_tree_scene(test::small_tree());
    scene.lod_budgets = {{std::begin(kBudgets), std::end(kBudgets)}};
    SimulationConfig config = test::windy_config();
    config.backend = BackendKind::cpu64;
    auto sim = std::move(Simulation::create(scene, config)).value();
    ASSERT_TRUE(sim->set_lod_bands({{10.0, 20.0, 30.0}, 0.2}).ok());
    uint64_t switches = 0;
    for (int frame = 0; frame < 50; ++frame) {
        const double distance = 10.0 + 1.5 * std::sin(0.9 * frame);  // within 10 +- 2
        switches += *sim->update_lod({distance, 0.0, 0.0});
        ASSERT_TRUE(sim->step(1).ok());
    }
    EXPECT_EQ(switches, 0u);
    EXPECT_EQ(*sim->update_lod({12.5, 0.0, 0.0}), 1u);  // past 10 * 1.2: a fade to level 1
    EXPECT_EQ(*sim->instance_lod_target(InstanceId(0)), 1u);
    for (int frame = 0; frame < 50; ++frame) {
        const double distance = 10.0 + 1.5 * std::sin(0.9 * frame);
        switches += *sim->update_lod({distance, 0.0, 0.0});
    }
    EXPECT_EQ(switches, 0u);
    EXPECT_EQ(*sim->update_lod({7.5, 0.0, 0.0}), 1u);  // below 10 * 0.8
    EXPECT_EQ(*sim->instance_lod_target(InstanceId(0)), 0u);
    EXPECT_EQ(*sim->update_lod({100.0, 0.0, 0.0}), 1u);  // far past every edge: the last level
    EXPECT_EQ(*sim->instance_lod_target(InstanceId(0)), 3u);
}

// The C ABI: budgets on the scene, switches by id, bands; bad input refused without a change.
TEST(LodSwitchC, SwitchesAndRefusals) {
    hmsm_scene* scene = nullptr;
    hmsm_tree* tree = nullptr;
    ASSERT_EQ(hmsm_tree_preset("paper-1", 0, &tree), HMSM_OK) << hmsm_status_message();
    ASSERT_EQ(hmsm_scene_create(&scene), HMSM_OK);
    uint32_t model = 0;
    ASSERT_EQ(hmsm_scene_add_model(scene, tree, "tree", &model), HMSM_OK);
    hmsm_instance instance;
    ASSERT_EQ(HMSM_INIT(hmsm_instance_init, &instance), HMSM_OK);
    ASSERT_EQ(hmsm_scene_add_instance(scene, &instance), HMSM_OK);
    const int32_t bad[] = {16, 0};
    EXPECT_EQ(hmsm_scene_set_lod_budgets(scene, 0, bad, 2), HMSM_INVALID_ARGUMENT);
    EXPECT_NE(std::string(hmsm_status_message()).find("budgets[1] = 0: below the trunk-only level"), std::string::npos);
    const int32_t budgets[] = {16, 1};
    ASSERT_EQ(hmsm_scene_set_lod_budgets(scene, 0, budgets, 2), HMSM_OK);
    hmsm_config config;
    ASSERT_EQ(HMSM_INIT(hmsm_config_init, &config), HMSM_OK);
    config.backend = HMSM_BACKEND_CPU64;
    hmsm_simulation* sim = nullptr;
    ASSERT_EQ(hmsm_simulation_create(scene, &config, &sim), HMSM_OK) << hmsm_status_message();
    ASSERT_EQ(hmsm_simulation_step(sim, 10), HMSM_OK);
    const hmsm_instance_id ids[] = {0};
    const uint32_t too_far[] = {3};
    EXPECT_EQ(hmsm_simulation_set_instance_lods(sim, ids, too_far, 1), HMSM_INVALID_ARGUMENT);
    EXPECT_NE(std::string(hmsm_status_message()).find("level 3 does not exist"), std::string::npos) << hmsm_status_message();
    const hmsm_instance_id unknown[] = {5};
    const uint32_t one[] = {1};
    EXPECT_EQ(hmsm_simulation_set_instance_lods(sim, unknown, one, 1), HMSM_INVALID_ARGUMENT);
    uint32_t level = 9;
    ASSERT_EQ(hmsm_simulation_instance_lod(sim, 0, &level), HMSM_OK);
    EXPECT_EQ(level, 0u);
    const uint32_t coarsest[] = {2};
    ASSERT_EQ(hmsm_simulation_set_instance_lods(sim, ids, coarsest, 1), HMSM_OK) << hmsm_status_message();
    ASSERT_EQ(hmsm_simulation_instance_lod(sim, 0, &level), HMSM_OK);
    EXPECT_EQ(level, 2u);
    const double edges[] = {10.0, 20.0};
    EXPECT_EQ(hmsm_simulation_set_lod_bands(sim, edges, 2, 1.5), HMSM_INVALID_ARGUMENT);
    ASSERT_EQ(hmsm_simulation_set_lod_bands(sim, edges, 2, 0.1), HMSM_OK);
    // The fade: a bound of 0 reads nothing (accepted); one past a metre is refused, naming it.
    EXPECT_EQ(hmsm_simulation_set_lod_fade(sim, 30, 2.0), HMSM_INVALID_ARGUMENT);
    EXPECT_NE(std::string(hmsm_status_message()).find("fade_bound_m"), std::string::npos) << hmsm_status_message();
    ASSERT_EQ(hmsm_simulation_set_lod_fade(sim, 30, 0.0), HMSM_OK) << hmsm_status_message();
    const double viewer[3] = {0.0, 0.0, 0.0};
    uint64_t switched = 0;
    ASSERT_EQ(hmsm_simulation_update_lod(sim, viewer, &switched), HMSM_OK);
    EXPECT_EQ(switched, 1u);
    ASSERT_EQ(hmsm_simulation_instance_lod(sim, 0, &level), HMSM_OK);
    EXPECT_EQ(level, 0u);
    ASSERT_EQ(hmsm_simulation_step(sim, 10), HMSM_OK);
    // An arrival on the coarsest level, and one on a level the model lacks.
    instance.level = 2;
    hmsm_instance_id arrived = 0;
    ASSERT_EQ(hmsm_simulation_add_instances_with_ids(sim, &instance, 1, &arrived), HMSM_OK) << hmsm_status_message();
    ASSERT_EQ(hmsm_simulation_instance_lod(sim, arrived, &level), HMSM_OK);
    EXPECT_EQ(level, 2u);
    hmsm_instance listed[2];
    ASSERT_EQ(HMSM_INIT(hmsm_instance_init, &listed[0]), HMSM_OK);
    size_t listed_count = 0;
    ASSERT_EQ(hmsm_simulation_instances(sim, listed, 2, &listed_count), HMSM_OK);
    EXPECT_EQ(listed[1].level, 2u);
    instance.level = 3;
    EXPECT_EQ(hmsm_simulation_add_instances(sim, &instance, 1), HMSM_INVALID_ARGUMENT);
    EXPECT_NE(std::string(hmsm_status_message()).find("level 3 does not exist"), std::string::npos);
    hmsm_simulation_destroy(sim);
    hmsm_scene_destroy(scene);
    hmsm_tree_destroy(tree);
}

}  // namespace
}  // namespace hmsm
