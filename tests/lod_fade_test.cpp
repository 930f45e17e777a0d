// Fades to coarser levels of detail (docs/model.md 3.12, docs/driving.md): an instantaneous
// coarsening pops the folded branches' deflection; a fade relaxes them over the steps first (in
// the backend's pass 2, exactly to rest after fade_steps steps run in one call), so
// that the switch moves no vertex by more than the bound, nor more than the tree moves in a
// frame, and the relaxation itself adds at most a centimetre a frame. Every backend agrees with
// cpu64 through fades, a refine during a fade returns without a jump, and bad fade settings
// are refused without a change.
#include "simulation_access.h"
#include "test_trees.h"

#include <hmsm/hmsm_c.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace hmsm {
namespace {

constexpr double kTarget = 0.01;  // m: what a switch may move a vertex by (docs/model.md 3.12)
constexpr double kFadeMotion = 1.5;

std::vector<double> positions(const Simulation& sim) {
    std::vector<double> values;
    const Status read = sim.read(Output::vertex_positions, values);
    EXPECT_TRUE(read.ok()) << read.message();
    return values;
}

double largest_move(const std::vector<double>& a, const std::vector<double>& b) {
    double largest = 0.0;
    for (size_t k = 0; k + 2 < a.size() && k + 2 < b.size(); k += 3)
        largest = std::max(largest, std::hypot(a[k] - b[k], a[k + 1] - b[k + 1], a[k + 2] - b[k + 2]));
    return largest;
}

struct Case {
    const char* name;
    Dynamics dynamics;
    bool preset;  // paper-1 (budgets 256, 64, 16, 1); else the deep test tree (6, 3, 1)
    bool storm;   // the gusty test wind (test::windy_config); else the default breeze, as the bench
    uint32_t fade_steps;
};

/// The deep test tree is stiff: a storm on it (wind scale 100, 300 under the coupled dynamics'
/// damping) bends its branches by centimetres, as the gusty wind bends paper-1's by decimetres.
constexpr double kDeepWindScale = 100.0, kDeepCoupledWindScale = 300.0;

Scene case_scene(const Case& c) {
    Scene scene = single_tree_scene(c.preset ? *generate_preset("paper-1") : test::deep_tree(4));
    if (!c.preset) scene.instances[0].wind_scale = c.dynamics == Dynamics::paper ? kDeepWindScale : kDeepCoupledWindScale;
    scene.lod_budgets = {c.preset ? std::vector<int32_t>{256, 64, 16, 1} : std::vector<int32_t>{6, 3, 1}};
    return scene;
}

SimulationConfig case_config(const Case& c) {
    SimulationConfig config = c.storm ? test::windy_config() : SimulationConfig{};
    config.backend = BackendKind::cpu64;
    config.model.dynamics = c.dynamics;
    return config;
}

std::unique_ptr<Simulation> create(const Case& c, uint32_t fade_steps) {
    auto sim = Simulation::create(case_scene(c), case_config(c));
    EXPECT_TRUE(sim.ok()) << sim.status().message();
    if (!sim) return nullptr;
    LodBands bands;
    bands.fade_steps = fade_steps;
    EXPECT_TRUE((*sim)->set_lod_bands(bands).ok());
    return std::move(sim).value();
}

class LodFade : public ::testing::TestWithParam<Case> {};

// Fade off: the switch to the trunk-only level pops by more than the target and than a frame's
// motion. Fade on: the instance keeps its level while the fade runs, and the switch moves no
// vertex by more than the bound, below the frame's own motion. While it fades, no frame moves the
// tree by more than the target or kFadeMotion times the unfaded tree's largest frame motion over
// the same frames: holding a branch against the wind removes, each step, what the wind adds.
TEST_P(LodFade, CoarseningSwitchPopsWithoutFadeAndNotWithIt) {
    const Case& c = GetParam();
    const InstanceId id{0};
    auto instant = create(c, 0), faded = create(c, c.fade_steps), twin = create(c, 0);
    ASSERT_TRUE(instant && faded && twin);
    const uint32_t coarsest = instant->lod_level_count(0) - 1;
    // 2.5 s into the wind, its branches bent. The comparison is at one moment: the stiff deep
    // tree's frame motion follows the 8.75 Hz term of the storm's profile, so in some frames
    // it moves by more than the pop a switch there would make.
    for (Simulation* s : {instant.get(), faded.get(), twin.get()}) ASSERT_TRUE(s->step(300).ok());

    auto before = positions(*instant);
    ASSERT_TRUE(instant->step(1).ok());
    auto frame = positions(*instant);
    ASSERT_EQ(*instant->request_instance_lods({&id, 1}, {&coarsest, 1}), 1u);
    EXPECT_EQ(*instant->instance_lod(id), coarsest);
    const double pop = largest_move(frame, positions(*instant)), pop_motion = largest_move(before, frame);
    std::printf("[ lod fade ] %s without fade: jump %.4g m, frame motion %.4g m\n", c.name, pop, pop_motion);
    EXPECT_GT(pop, kTarget);
    EXPECT_GT(pop, pop_motion);

    ASSERT_EQ(*faded->request_instance_lods({&id, 1}, {&coarsest, 1}), 1u);
    EXPECT_EQ(*faded->instance_lod(id), 0u);
    EXPECT_EQ(*faded->instance_lod_target(id), coarsest);
    EXPECT_EQ(faded->fading_instance_count(), 1u);
    double fading_motion = 0.0, own_motion = 0.0, jump = -1.0, jump_motion = 0.0;
    auto a = positions(*faded), b = positions(*twin);
    for (uint32_t k = 0; k <= c.fade_steps + 1 && jump < 0.0; ++k) {
        ASSERT_TRUE(faded->step(1).ok());
        ASSERT_TRUE(twin->step(1).ok());
        auto a1 = positions(*faded), b1 = positions(*twin);
        const double motion = largest_move(a, a1);
        fading_motion = std::max(fading_motion, motion);
        own_motion = std::max(own_motion, largest_move(b, b1));
        // A fade that ended switches at the next call: a request for the level it heads for.
        ASSERT_TRUE(faded->request_instance_lods({&id, 1}, {&coarsest, 1}).ok());
        if (*faded->instance_lod(id) == coarsest) {
            jump = largest_move(a1, positions(*faded));
            jump_motion = motion;
        }
        a = positions(*faded);
        b = std::move(b1);
    }
    std::printf("[ lod fade ] %s with a %u-step fade: jump %.4g m, frame motion %.4g m; fading tree %.4g m a "
                "frame at most, unfaded %.4g m\n",
                c.name, c.fade_steps, jump, jump_motion, fading_motion, own_motion);
    ASSERT_GE(jump, 0.0) << "the fade never switched";
    EXPECT_EQ(faded->fading_instance_count(), 0u);
    EXPECT_LE(jump, LodBands{}.fade_bound_m);
    EXPECT_LT(jump, jump_motion);
    EXPECT_LE(fading_motion, std::max(kTarget, kFadeMotion * own_motion));
}

INSTANTIATE_TEST_SUITE_P(Trees, LodFade,
                         ::testing::Values(Case{"deep tree, paper", Dynamics::paper, false, true, LodBands{}.fade_steps},
                                           Case{"deep tree, coupled", Dynamics::coupled, false, true, LodBands{}.fade_steps},
                                           Case{"paper-1, paper", Dynamics::paper, true, false, LodBands{}.fade_steps},
                                           // A storm bends paper-1 by metres: a fade removes 1/F of that a step.
                                           Case{"paper-1 in a storm, paper", Dynamics::paper, true, true, 120}),
                         [](const ::testing::TestParamInfo<Case>& info) {
                             return std::string(info.param.preset ? "paper1_" : "deep_") +
                                    (info.param.dynamics == Dynamics::paper ? "paper" : "coupled") +
                                    (info.param.preset && info.param.storm ? "_storm" : "");
                         });

Scene fade_forest(double wind_scale) {
    Scene scene = *grid_scene(test::small_tree(), 4, 5.0, 11);
    scene.models.push_back(test::deep_tree(4));
    scene.model_names.push_back("deep");
    scene.instances.insert(scene.instances.begin() + 1, Instance{1, {-6, 0, 8}, 0.4});
    scene.instances.push_back({1, {9, 0, -3}, 1.9, 0.7, 0.3});
    constexpr int32_t budgets[] = {6, 3, 1};
    scene.lod_budgets = {{std::begin(budgets), std::end(budgets)}, {std::begin(budgets), std::end(budgets)}};
    for (Instance& instance : scene.instances) instance.wind_scale = wind_scale;
    return scene;
}

std::string backend_name(const ::testing::TestParamInfo<std::tuple<BackendKind, Dynamics>>& info) {
    std::string name = to_string(std::get<0>(info.param));
    std::replace(name.begin(), name.end(), '-', '_');
    return name + (std::get<1>(info.param) == Dynamics::paper ? "_paper" : "_coupled");
}

class LodFadeBackends : public ::testing::TestWithParam<std::tuple<BackendKind, Dynamics>> {};

// Fades started, retargeted coarser, interrupted by a refine and run to their switch, by handle
// and by the bands: within the agreement suite's tolerance of cpu64 doing the same, and on the
// same levels once every fade has switched.
TEST_P(LodFadeBackends, AgreesWithCpu64ThroughFades) {
    const auto [kind, dynamics] = GetParam();
    if (kind == BackendKind::cpu64) GTEST_SKIP() << "cpu64 is the oracle";
    SimulationConfig config = test::windy_config();
    config.model.dynamics = dynamics;
    std::string skip;
    auto sim = test::create_simulation_or_skip(fade_forest(1.0), config, kind, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    auto oracle = test::create_simulation_or_skip(fade_forest(1.0), config, BackendKind::cpu64, skip);
    ASSERT_TRUE(sim && oracle);
    auto both = [&](auto&& action) {
        ASSERT_TRUE(action(*sim).ok());
        ASSERT_TRUE(action(*oracle).ok());
    };
    auto compare = [&](const char* when, double tolerance) {
        std::vector<double> a, b;
        ASSERT_TRUE(sim->read(Output::node_positions, a).ok());
        ASSERT_TRUE(oracle->read(Output::node_positions, b).ok());
        ASSERT_EQ(a.size(), b.size()) << when;
        EXPECT_LE(test::max_abs_difference(a, b), tolerance) << when;
    };
    const InstanceId ids[] = {InstanceId(0), InstanceId(1), InstanceId(3), InstanceId(5)};
    const uint32_t coarser[] = {1, 2, 2, 3};
    const uint32_t coarsest[] = {3, 3};
    const uint32_t back[] = {0};
    // A bound of 10 µm: the test trees bend by millimetres in this wind.
    both([](Simulation& s) { return s.set_lod_bands({{6.0, 9.0, 12.0}, 0.1, 40, 1e-5}); });
    both([](Simulation& s) { return s.step(60); });
    both([&](Simulation& s) { return s.request_instance_lods(ids, coarser).status(); });
    EXPECT_EQ(sim->fading_instance_count(), 4u);
    EXPECT_EQ(oracle->fading_instance_count(), 4u);
    both([](Simulation& s) { return s.step(15); });
    compare("mid-fade", 1e-3);
    both([&](Simulation& s) { return s.request_instance_lods({ids, 2}, coarsest).status(); });
    both([&](Simulation& s) { return s.request_instance_lods({ids + 2, 1}, back).status(); });
    both([](Simulation& s) { return s.step(20); });
    compare("after a retarget and a refine", 1e-3);
    both([](Simulation& s) { return s.step(40); });
    both([](Simulation& s) { return s.update_lod({20.0, 1.0, 20.0}).status(); });
    both([](Simulation& s) { return s.step(45); });
    both([](Simulation& s) { return s.update_lod({20.0, 1.0, 20.0}).status(); });
    EXPECT_EQ(sim->fading_instance_count(), 0u);
    EXPECT_EQ(oracle->fading_instance_count(), 0u);
    for (size_t i = 0; i < sim->instance_count(); ++i) EXPECT_EQ(sim->instances()[i].model, oracle->instances()[i].model);
    both([](Simulation& s) { return s.step(10); });
    compare("after every fade switched", 1e-3);
}

INSTANTIATE_TEST_SUITE_P(Backends, LodFadeBackends,
                         ::testing::Combine(::testing::Values(BackendKind::cpu64, BackendKind::cpu,
                                                              BackendKind::cpu_parallel, BackendKind::vulkan,
                                                              BackendKind::cuda),
                                            ::testing::Values(Dynamics::paper, Dynamics::coupled)),
                         backend_name);

/// Per instance: how many of its chains have S = V = 0 exactly, and how many do not.
std::vector<std::pair<uint32_t, uint32_t>> resting_chains(const Simulation& sim) {
    std::vector<double> angles;
    EXPECT_TRUE(sim.read(Output::chain_angles, angles).ok());
    std::vector<std::pair<uint32_t, uint32_t>> counts;
    size_t at = 0;
    for (const Instance& instance : sim.instances()) {
        auto& [resting, moving] = counts.emplace_back(0u, 0u);
        for (size_t c = 0; c < sim.hierarchy(instance.model).chains.size(); ++c, at += 4) {
            const bool rest = at + 3 < angles.size() && angles[at] == 0.0 && angles[at + 1] == 0.0 &&
                              angles[at + 2] == 0.0 && angles[at + 3] == 0.0;
            ++(rest ? resting : moving);
        }
    }
    EXPECT_EQ(at, angles.size());
    return counts;
}

class LodFadeDevice : public ::testing::TestWithParam<std::tuple<BackendKind, Dynamics>> {};

// The fade runs in the backend's pass 2: fade_steps steps run in one call leave the chains the
// target level folds exactly at rest (S = V = 0), as many as the level folds, while every chain
// it keeps still moves; the instances switch at the next call, and the run agrees with cpu64.
TEST_P(LodFadeDevice, FoldedChainsRestExactlyAfterOneCall) {
    const auto [kind, dynamics] = GetParam();
    SimulationConfig config = test::windy_config();
    config.model.dynamics = dynamics;
    std::string skip;
    auto sim = test::create_simulation_or_skip(fade_forest(kDeepWindScale), config, kind, skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    auto oracle = test::create_simulation_or_skip(fade_forest(kDeepWindScale), config, BackendKind::cpu64, skip);
    ASSERT_TRUE(sim && oracle);
    constexpr uint32_t kSteps = 30;
    for (Simulation* s : {sim.get(), oracle.get()}) {
        ASSERT_TRUE(s->set_lod_bands({{6.0, 9.0, 12.0}, 0.1, kSteps, 1e-5}).ok());
        ASSERT_TRUE(s->step(60).ok());
    }
    const InstanceId ids[] = {InstanceId(0), InstanceId(1), InstanceId(3)};
    const uint32_t levels[] = {2, 3, 2};
    std::vector<uint32_t> chains_before;
    for (const Instance& instance : sim->instances())
        chains_before.push_back(uint32_t(sim->hierarchy(instance.model).chains.size()));
    for (Simulation* s : {sim.get(), oracle.get()}) {
        ASSERT_TRUE(s->request_instance_lods(ids, levels).ok());
        ASSERT_EQ(s->fading_instance_count(), 3u) << "the trees sway: their switches fade";
        ASSERT_TRUE(s->step(kSteps).ok());
        EXPECT_EQ(s->fading_instance_count(), 3u) << "over, switched at the next call";
    }
    std::vector<double> a, b;
    ASSERT_TRUE(sim->read(Output::node_positions, a).ok());
    ASSERT_TRUE(oracle->read(Output::node_positions, b).ok());
    ASSERT_EQ(a.size(), b.size());
    EXPECT_LE(test::max_abs_difference(a, b), 1e-3);
    const auto counts = resting_chains(*sim);
    ASSERT_TRUE(sim->step(1).ok());
    EXPECT_EQ(sim->fading_instance_count(), 0u);
    for (size_t i = 0; i < counts.size(); ++i) {
        const uint32_t kept = uint32_t(sim->hierarchy(sim->instances()[i].model).chains.size());
        EXPECT_EQ(counts[i].first, chains_before[i] - kept) << "instance " << i << ": the folded chains at rest";
        EXPECT_EQ(counts[i].second, kept) << "instance " << i << ": the kept chains move";
    }
    EXPECT_EQ(*sim->instance_lod(InstanceId(1)), 3u);
}

INSTANTIATE_TEST_SUITE_P(Backends, LodFadeDevice,
                         ::testing::Combine(::testing::Values(BackendKind::cpu64, BackendKind::cpu,
                                                              BackendKind::cpu_parallel, BackendKind::vulkan,
                                                              BackendKind::cuda),
                                            ::testing::Values(Dynamics::paper, Dynamics::coupled)),
                         backend_name);

std::unique_ptr<Simulation> windy_forest() {
    SimulationConfig config = test::windy_config();
    config.backend = BackendKind::cpu64;
    auto sim = Simulation::create(fade_forest(kDeepWindScale), config);
    EXPECT_TRUE(sim.ok()) << sim.status().message();
    return sim ? std::move(sim).value() : nullptr;
}

// An instance at rest switches at once; a refine during a fade (back to the level the instance
// runs) ends the fade with no jump and no switch; a retarget coarser still ends on the coarser
// level; a paused instance's fade waits; a removed instance's fade is dropped.
TEST(LodFadeRequests, InterruptRetargetPauseRemoveAndRest) {
    auto sim = windy_forest();
    ASSERT_TRUE(sim);
    const InstanceId small{0}, deep{1}, paused{2}, removed{3};
    const uint32_t two = 2, three = 3, zero = 0;
    ASSERT_EQ(*sim->request_instance_lods({&deep, 1}, {&two, 1}), 1u);
    EXPECT_EQ(*sim->instance_lod(deep), 2u) << "an instance at rest switches at once";
    EXPECT_EQ(sim->fading_instance_count(), 0u);
    ASSERT_TRUE(sim->set_instance_lod(deep, 0).ok());
    ASSERT_TRUE(sim->step(120).ok());
    ASSERT_TRUE(sim->set_instance_active(2, false).ok());

    const InstanceId all[] = {small, deep, paused, removed};
    const uint32_t levels[] = {2, 2, 2, 2};  // level 1 keeps every chain of both trees
    ASSERT_EQ(*sim->request_instance_lods(all, levels), 4u);
    EXPECT_EQ(sim->fading_instance_count(), 4u);
    ASSERT_TRUE(sim->step(10).ok());
    const auto mid = positions(*sim);
    ASSERT_EQ(*sim->request_instance_lods({&small, 1}, {&zero, 1}), 1u);
    const auto refined = positions(*sim);
    ASSERT_EQ(refined.size(), mid.size());
    for (size_t k = 0; k < mid.size(); ++k)
        ASSERT_EQ(refined[k], mid[k]) << "a refine to the running level moves nothing: element " << k;
    EXPECT_EQ(*sim->instance_lod(small), 0u);
    EXPECT_EQ(*sim->instance_lod_target(small), 0u);
    ASSERT_EQ(*sim->request_instance_lods({&deep, 1}, {&three, 1}), 1u);
    EXPECT_EQ(*sim->instance_lod(deep), 0u);
    EXPECT_EQ(*sim->instance_lod_target(deep), 3u);
    ASSERT_TRUE(sim->remove_instances_by_id({&removed, 1}).ok());
    EXPECT_EQ(sim->fading_instance_count(), 2u) << "a removed instance's fade ends with it";
    ASSERT_TRUE(sim->step(LodBands{}.fade_steps).ok());
    ASSERT_EQ(*sim->request_instance_lods({&deep, 1}, {&three, 1}), 0u);  // the ended fade switches
    EXPECT_EQ(*sim->instance_lod(deep), 3u);
    EXPECT_EQ(*sim->instance_lod(paused), 0u) << "a paused instance's fade waits";
    EXPECT_EQ(sim->fading_instance_count(), 1u);
    ASSERT_TRUE(sim->set_instance_active(2, true).ok());
    ASSERT_TRUE(sim->step(LodBands{}.fade_steps).ok());
    ASSERT_TRUE(sim->update_lod({0.0, 0.0, 0.0}).ok());  // no edges: level 0 wanted, after the switch
    EXPECT_EQ(sim->fading_instance_count(), 0u);
    EXPECT_EQ(*sim->instance_lod(paused), 0u);
    EXPECT_EQ(*sim->instance_lod(deep), 0u);
}

// With fade_bound_m 0 no request reads the state: an instance at rest fades as any other (and
// switches once its fade is over), where the default bound measures it with a read and
// switches it at once.
TEST(LodFadeRequests, NoBoundReadsNothingAndFadesEvenAtRest) {
    auto sim = windy_forest();
    ASSERT_TRUE(sim);
    const uint64_t& reads = detail::SimulationAccess::impl(*sim).at_rest_reads_;
    const InstanceId small{0}, deep{1};
    const uint32_t two = 2;
    ASSERT_EQ(*sim->request_instance_lods({&deep, 1}, {&two, 1}), 1u);
    EXPECT_EQ(*sim->instance_lod(deep), 2u) << "at rest: switched at once";
    EXPECT_EQ(reads, 1u);
    LodBands bands = sim->lod_bands();
    bands.fade_bound_m = 0.0;
    ASSERT_TRUE(sim->set_lod_bands(bands).ok());
    ASSERT_EQ(*sim->request_instance_lods({&small, 1}, {&two, 1}), 1u);
    EXPECT_EQ(*sim->instance_lod(small), 0u) << "at rest too, but fading";
    EXPECT_EQ(*sim->instance_lod_target(small), 2u);
    EXPECT_EQ(sim->fading_instance_count(), 1u);
    EXPECT_EQ(reads, 1u) << "the state was read";
    ASSERT_TRUE(sim->step(bands.fade_steps).ok());
    ASSERT_TRUE(sim->step(1).ok());  // switches the fades that are over first
    EXPECT_EQ(*sim->instance_lod(small), 2u) << "the fade is over: switched";
    EXPECT_EQ(sim->fading_instance_count(), 0u);
    EXPECT_EQ(reads, 1u);
}

// A fade word names the level faded to in 7 bits: a model with more than 128 levels (level 0
// included) is refused at create, naming the model; 128 levels are fine.
TEST(LodFadeInput, MoreLevelsThanAFadeWordNamesAreRefused) {
    Scene scene = single_tree_scene(test::small_tree());
    scene.lod_budgets = {std::vector<int32_t>(128, 1)};
    auto refused = Simulation::create(scene, SimulationConfig{});
    ASSERT_FALSE(refused.ok());
    EXPECT_EQ(refused.status().code(), ErrorCode::invalid_argument);
    EXPECT_NE(refused.status().message().find("'" + scene.model_names[0] + "': 129 levels of detail, at most 128"),
              std::string::npos)
        << refused.status().message();
    scene.lod_budgets[0].pop_back();
    auto created = Simulation::create(scene, SimulationConfig{});
    EXPECT_TRUE(created.ok()) << created.status().message();
}

// Bad fade settings and bad requests are refused, naming the problem, and change nothing.
TEST(LodFadeInput, BadSettingsAndRequestsChangeNothing) {
    auto sim = windy_forest();
    ASSERT_TRUE(sim);
    const LodBands good{{10.0, 20.0}, 0.1, 30, 2e-3};
    ASSERT_TRUE(sim->set_lod_bands(good).ok());
    auto refused = [&](LodBands bands, const char* names) {
        const Status status = sim->set_lod_bands(bands);
        EXPECT_EQ(status.code(), ErrorCode::invalid_argument);
        EXPECT_NE(status.message().find(names), std::string::npos) << status.message();
        EXPECT_EQ(sim->lod_bands().fade_steps, good.fade_steps);
        EXPECT_EQ(sim->lod_bands().fade_bound_m, good.fade_bound_m);
    };
    refused({{10.0}, 0.1, kMaxLodFadeSteps + 1, 1e-3}, "fade_steps");
    refused({{10.0}, 0.1, 30, -1e-3}, "fade_bound_m");
    refused({{10.0}, 0.1, 30, std::nan("")}, "fade_bound_m");
    refused({{10.0}, 0.1, 30, 2.0}, "fade_bound_m");

    ASSERT_TRUE(sim->step(60).ok());
    const InstanceId id{0};
    const uint32_t two = 2;
    ASSERT_EQ(*sim->request_instance_lods({&id, 1}, {&two, 1}), 1u);
    const auto before = positions(*sim);
    auto request_refused = [&](std::span<const InstanceId> ids, std::span<const uint32_t> levels, const char* names) {
        Result<uint64_t> done = sim->request_instance_lods(ids, levels);
        ASSERT_FALSE(done.ok());
        EXPECT_NE(done.status().message().find(names), std::string::npos) << done.status().message();
        EXPECT_EQ(sim->fading_instance_count(), 1u);
        EXPECT_EQ(*sim->instance_lod_target(id), 2u);
        EXPECT_EQ(positions(*sim), before);
    };
    const InstanceId twice[] = {id, id}, unknown[] = {InstanceId(99)};
    const uint32_t levels2[] = {0, 0}, nine[] = {9};
    request_refused(twice, levels2, "listed twice");
    request_refused(unknown, {levels2, 1}, "never given");
    request_refused({&id, 1}, nine, "level 9 does not exist");
    request_refused({&id, 1}, levels2, "1 ids but 2 levels");

    hmsm_simulation* none = nullptr;
    EXPECT_EQ(hmsm_simulation_set_lod_fade(none, 10, 1e-3), HMSM_INVALID_ARGUMENT);
}

}  // namespace
}  // namespace hmsm
