// Live control (docs/model.md 3.9): every backend follows cpu64 through schedules that change
// everything; no change moves a tree by itself; rejected calls change nothing.
#include "test_trees.h"

#include "simulation_access.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace hmsm {
namespace {

std::vector<double> read(const Simulation& sim, Output output) {
    std::vector<double> values;
    EXPECT_TRUE(sim.read(output, values).ok());
    return values;
}

Scene mixed_scene() {
    Scene scene = *grid_scene(test::small_tree(), 4, 5.0, 3);
    scene.models.push_back(test::deep_tree(5));
    scene.model_names.push_back("deep");
    scene.instances.push_back({1, {-3, 0, 7}, 0.8});
    scene.instances.push_back({0, {6, 0, -2}, 0.1, 0.6, 0.25});
    scene.instances[1].active = false;
    return scene;
}

/// Everything a schedule can change, between steps; returns false on a failed call.
using Schedule = std::function<void(Simulation&, uint32_t step)>;

void everything(Simulation& sim, uint32_t n) {
    Wind wind = sim.wind();
    std::vector<ForceField> fields;
    switch (n) {
        case 20:
            wind.profile = WindProfile::turbulent;
            wind.strength = 6.0;
            wind.turbulence = 0.8;
            wind.seed = 12345678901234567ull;
            ASSERT_TRUE(sim.set_wind(wind).ok());
            break;
        case 45:
            wind.direction = {0.2, 0.0, 1.0};
            wind.frequency = 0.45;
            wind.front_speed = 2.0;
            ASSERT_TRUE(sim.set_wind(wind).ok());
            ASSERT_TRUE(sim.set_instance_wind_scale(0, 0.3).ok());
            ASSERT_TRUE(sim.set_instance_wind_phase(2, 0.5).ok());
            ASSERT_TRUE(sim.set_instance_active(1, true).ok());
            break;
        case 60:
            fields.resize(2);
            fields[0].center = {0, 3, 0};
            fields[0].radius = 6.0;
            fields[0].directional = {0, 0, 8};
            fields[1].kind = ForceField::Kind::radial;
            fields[1].center = {-3, 2, 7};
            fields[1].radius = 4.0;
            fields[1].radial = 10.0;
            ASSERT_TRUE(sim.set_force_fields(fields).ok());
            ASSERT_TRUE(sim.set_instance_active(3, false).ok());
            break;
        case 80: {
            const uint64_t gone[] = {0, 4};
            ASSERT_TRUE(sim.remove_instances(gone).ok());
            const Instance added[] = {{1, {9, 0, 9}, 2.0, 1.2, 0.1}, {0, {-8, 0, 1}, 0.5}};
            ASSERT_TRUE(sim.add_instances(added).ok());
            ASSERT_TRUE(sim.set_force_fields({}).ok());
            wind.profile = WindProfile::y1;
            wind.frequency = 0.1;
            ASSERT_TRUE(sim.set_wind(wind).ok());
            break;
        }
        case 100:
            ASSERT_TRUE(sim.set_instance_active(1, true).ok());  // instance 3 before the removal
            break;
        default: break;
    }
}

void run_schedule(Simulation& sim, uint32_t steps, const Schedule& schedule) {
    for (uint32_t n = 1; n <= steps; ++n) {
        schedule(sim, n);
        ASSERT_TRUE(sim.step().ok()) << n;
    }
}

double tree_height(const Simulation& sim) {
    double height = 0.0;
    for (size_t m = 0; m < sim.scene().models.size(); ++m) {
        double lo = 1e300, hi = -1e300;
        for (const TreeNode& node : sim.scene().models[m].nodes) {
            lo = std::min(lo, node.position.y);
            hi = std::max(hi, node.position.y);
        }
        height = std::max(height, hi - lo);
    }
    return height;
}

class LiveAgreement : public ::testing::TestWithParam<BackendKind> {};

TEST_P(LiveAgreement, FollowsCpu64ThroughASchedule) {
    for (Composition composition : {Composition::pointer_jumping, Composition::level_by_level, Composition::path_walk}) {
        SCOPED_TRACE(to_string(composition));
        SimulationConfig config;
        config.composition = composition;
        std::string skip;
        auto sim = test::create_simulation_or_skip(mixed_scene(), config, GetParam(), skip);
        if (!skip.empty()) GTEST_SKIP() << skip;
        auto oracle = test::create_simulation_or_skip(mixed_scene(), config, BackendKind::cpu64, skip);
        ASSERT_TRUE(sim && oracle);
        for (uint32_t n = 1; n <= 130; ++n) {
            everything(*sim, n);
            everything(*oracle, n);
            ASSERT_TRUE(sim->step().ok());
            ASSERT_TRUE(oracle->step().ok());
        }
        ASSERT_EQ(sim->instance_count(), oracle->instance_count());
        const double height = tree_height(*oracle);
        for (Output output : {Output::node_positions, Output::chain_origins, Output::chain_rotations,
                              Output::vertex_positions}) {
            auto a = read(*sim, output), b = read(*oracle, output);
            ASSERT_EQ(a.size(), b.size());
            ASSERT_TRUE(test::all_finite(a));
            const double scale = output == Output::chain_rotations ? 1.0 : height;
            EXPECT_LE(test::max_abs_difference(a, b) / scale, 1e-4) << int(output);
        }
    }
}

// Through adds, removals (whose moved instances recompute passes 4, 6 and 7 alone), pauses and
// wind changes, path walk stays level by level bit for bit on the CPU.
TEST(LiveAgreementPathWalk, EqualsLevelByLevelBitwiseThroughASchedule) {
    SimulationConfig walk_config, level_config;
    walk_config.backend = level_config.backend = BackendKind::cpu;
    walk_config.composition = Composition::path_walk;
    level_config.composition = Composition::level_by_level;
    auto walk = Simulation::create(mixed_scene(), walk_config);
    auto level = Simulation::create(mixed_scene(), level_config);
    ASSERT_TRUE(walk.ok() && level.ok());
    for (uint32_t n = 1; n <= 130; ++n) {
        everything(**walk, n);
        everything(**level, n);
        ASSERT_TRUE((*walk)->step().ok());
        ASSERT_TRUE((*level)->step().ok());
    }
    for (Output output : {Output::node_positions, Output::chain_origins, Output::chain_rotations,
                          Output::vertex_positions, Output::joint_matrices})
        EXPECT_EQ(read(**walk, output), read(**level, output)) << int(output);
    // The schedule bent the trees, or equal outputs prove little.
    double largest_angle = 0.0;
    for (double a : read(**walk, Output::chain_angles)) largest_angle = std::max(largest_angle, std::abs(a));
    EXPECT_GT(largest_angle, 1e-3);
}

INSTANTIATE_TEST_SUITE_P(Backends, LiveAgreement,
                         ::testing::Values(BackendKind::cpu, BackendKind::vulkan, BackendKind::cuda),
                         test::BackendTestName());

class LiveControl : public ::testing::TestWithParam<BackendKind> {};

TEST_P(LiveControl, NoChangeMovesATree) {
    SimulationConfig config;
    config.wind.strength = 5.0;
    std::string skip;
    auto sim = test::create_simulation_or_skip(mixed_scene(), config, GetParam(), skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(sim->step(30).ok());
    auto unchanged = [&](const char* what, auto change) {
        SCOPED_TRACE(what);
        auto nodes = read(*sim, Output::node_positions);
        auto vertices = read(*sim, Output::vertex_positions);
        auto chains = read(*sim, Output::chain_rotations);
        change();
        EXPECT_EQ(read(*sim, Output::node_positions), nodes);
        EXPECT_EQ(read(*sim, Output::vertex_positions), vertices);
        EXPECT_EQ(read(*sim, Output::chain_rotations), chains);
        ASSERT_TRUE(sim->step(7).ok());
    };
    unchanged("wind", [&] {
        Wind w = sim->wind();
        w.profile = WindProfile::turbulent;
        w.direction = {0, 0, 1};
        w.frequency = 2.0;
        ASSERT_TRUE(sim->set_wind(w).ok());
    });
    unchanged("fields", [&] {
        ForceField f;
        f.center = {0, 2, 0};
        f.radius = 10;
        f.directional = {50, 0, 0};
        ASSERT_TRUE(sim->set_force_fields({&f, 1}).ok());
    });
    unchanged("instance settings", [&] {
        ASSERT_TRUE(sim->set_instance_wind_scale(2, 3.0).ok());
        ASSERT_TRUE(sim->set_instance_wind_phase(3, 0.7).ok());
        ASSERT_TRUE(sim->set_instance_active(0, false).ok());
    });
    // Remove and add: the survivors keep their pose exactly; an added tree stands at rest.
    auto nodes = read(*sim, Output::node_positions);
    auto vertices = read(*sim, Output::vertex_positions);
    const uint64_t gone[] = {1};
    const Instance added[] = {{0, {12, 0, 3}, 1.0}};
    std::vector<uint64_t> node_begin{0}, vertex_begin{0};
    for (const Instance& inst : sim->instances()) {
        node_begin.push_back(node_begin.back() + 3 * sim->scene().models[inst.model].nodes.size());
        vertex_begin.push_back(vertex_begin.back() + 3 * sim->mesh(inst.model).vertices.size());
    }
    ASSERT_TRUE(sim->remove_instances(gone).ok());
    ASSERT_TRUE(sim->add_instances(added).ok());
    ASSERT_EQ(sim->instance_count(), 6u);
    EXPECT_EQ(sim->instances()[5].origin, added[0].origin);
    auto after = read(*sim, Output::node_positions);
    auto after_vertices = read(*sim, Output::vertex_positions);
    std::vector<double> expected, expected_vertices;
    for (size_t i = 0; i < 6; ++i) {
        if (i == 1) continue;
        expected.insert(expected.end(), nodes.begin() + node_begin[i], nodes.begin() + node_begin[i + 1]);
        expected_vertices.insert(expected_vertices.end(), vertices.begin() + vertex_begin[i],
                                 vertices.begin() + vertex_begin[i + 1]);
    }
    ASSERT_LT(expected.size(), after.size());
    EXPECT_TRUE(std::equal(expected.begin(), expected.end(), after.begin()));
    EXPECT_TRUE(std::equal(expected_vertices.begin(), expected_vertices.end(), after_vertices.begin()));
    // The added tree: Ry(yaw) (p - p_root) + origin.
    const TreeModel& model = sim->scene().models[0];
    const size_t root = std::find_if(model.nodes.begin(), model.nodes.end(),
                                     [](const TreeNode& n) { return n.parent < 0; }) - model.nodes.begin();
    for (size_t n = 0; n < model.nodes.size(); ++n) {
        glm::dvec3 p = model.nodes[n].position - model.nodes[root].position;
        glm::dvec3 rest(std::cos(1.0) * p.x + std::sin(1.0) * p.z, p.y, -std::sin(1.0) * p.x + std::cos(1.0) * p.z);
        rest += added[0].origin;
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(after[expected.size() + 3 * n + k], rest[k], 1e-5);
    }
}

TEST_P(LiveControl, InactiveInstancesAreFrozen) {
    SimulationConfig config;
    config.wind.strength = 5.0;
    std::string skip;
    auto sim = test::create_simulation_or_skip(mixed_scene(), config, GetParam(), skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    ASSERT_TRUE(sim->step(20).ok());
    ASSERT_TRUE(sim->set_instance_active(2, false).ok());
    const size_t nodes = sim->scene().models[0].nodes.size() * 3;
    auto before = read(*sim, Output::node_positions);
    auto angles_before = read(*sim, Output::chain_angles);
    ASSERT_TRUE(sim->step(25).ok());
    auto after = read(*sim, Output::node_positions);
    // Instance 1 (inactive from the start) and 2 stay; 0 moves.
    EXPECT_TRUE(std::equal(before.begin() + nodes, before.begin() + 3 * nodes, after.begin() + nodes));
    EXPECT_FALSE(std::equal(before.begin(), before.begin() + nodes, after.begin()));
    // Reactivated, it resumes from its own state (S, V as left).
    const size_t chains = sim->hierarchy(0).chains.size() * 4;
    auto angles = read(*sim, Output::chain_angles);
    EXPECT_TRUE(std::equal(angles_before.begin() + 2 * chains, angles_before.begin() + 3 * chains,
                           angles.begin() + 2 * chains));
    ASSERT_TRUE(sim->set_instance_active(2, true).ok());
    ASSERT_TRUE(sim->step().ok());
    auto resumed = read(*sim, Output::node_positions);
    EXPECT_FALSE(std::equal(after.begin() + 2 * nodes, after.begin() + 3 * nodes, resumed.begin() + 2 * nodes));
    // Instance 1 never stepped: its pose is the rest pose.
    for (size_t k = nodes; k < 2 * nodes; ++k) EXPECT_EQ(resumed[k], before[k]);
}

// Paused instances between active ones stay inside their group's dispatches, whose threads skip
// them (a dispatch per run of active instances made a step with every tenth tree paused three
// times slower); only 16 or more paused in a row split a group, and paused instances at a
// group's ends are left out. The paused ones stay frozen bit for bit either way.
TEST_P(LiveControl, PausedInstancesStayInsideADispatchUnlessManyInARow) {
    std::string skip;
    auto sim = test::create_simulation_or_skip(*grid_scene(test::small_tree(), 40, 5.0, 3), SimulationConfig{},
                                               GetParam(), skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    const uint64_t chains = sim->hierarchy(0).chains.size();
    // The instances the wind_force dispatches cover, as [first, end) ranges.
    auto covered = [&] {
        std::vector<std::pair<uint32_t, uint32_t>> ranges;
        for (const detail::Dispatch& d : detail::step_program_of(*sim))
            if (d.pass == Pass::wind_force)
                ranges.push_back({d.constants.instance_begin,
                                  d.constants.instance_begin + uint32_t(d.constants.element_count / chains)});
        return ranges;
    };
    auto set_active = [&](uint32_t first, uint32_t end, uint32_t stride, bool active) {
        for (uint32_t i = first; i < end; i += stride) ASSERT_TRUE(sim->set_instance_active(i, active).ok());
    };
    ASSERT_TRUE(sim->step(3).ok());
    set_active(1, 40, 4, false);  // 1, 5, ..., 37: one paused instance between active ones
    const auto frozen = read(*sim, Output::node_positions);
    ASSERT_TRUE(sim->step(5).ok());
    EXPECT_EQ(covered(), (std::vector<std::pair<uint32_t, uint32_t>>{{0, 40}}));
    const auto moved = read(*sim, Output::node_positions);
    const size_t nodes = frozen.size() / 40;
    for (uint32_t i = 0; i < 40; ++i) {
        const bool same = std::equal(frozen.begin() + i * nodes, frozen.begin() + (i + 1) * nodes, moved.begin() + i * nodes);
        EXPECT_EQ(same, i % 4 == 1) << "instance " << i;
    }
    set_active(1, 40, 4, true);
    set_active(0, 20, 1, false);   // 20 in a row: the group splits
    set_active(22, 38, 1, false);  // 16 in a row, too
    set_active(39, 40, 1, false);  // the last: left out
    ASSERT_TRUE(sim->step().ok());
    EXPECT_EQ(covered(), (std::vector<std::pair<uint32_t, uint32_t>>{{20, 22}, {38, 39}}));
    set_active(20, 22, 1, false);
    set_active(38, 39, 1, false);
    ASSERT_TRUE(sim->step().ok());
    EXPECT_TRUE(covered().empty());
}

TEST_P(LiveControl, RejectedCallsChangeNothing) {
    SimulationConfig config;
    config.wind.strength = 3.0;
    std::string skip;
    auto sim = test::create_simulation_or_skip(mixed_scene(), config, GetParam(), skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    auto twin = test::create_simulation_or_skip(mixed_scene(), config, GetParam(), skip);
    ASSERT_TRUE(sim && twin);
    ASSERT_TRUE(sim->step(10).ok());
    ASSERT_TRUE(twin->step(10).ok());
    auto message = [](const Status& s) { return s.ok() ? std::string("accepted") : s.message(); };
    EXPECT_NE(message(sim->set_instance_wind_scale(99, 1.0)).find("instance 99"), std::string::npos);
    EXPECT_NE(message(sim->set_instance_wind_scale(0, -1.0)).find("wind scale"), std::string::npos);
    EXPECT_NE(message(sim->set_instance_wind_scale(0, std::nan(""))).find("wind scale"), std::string::npos);
    EXPECT_NE(message(sim->set_instance_wind_phase(0, INFINITY)).find("wind phase"), std::string::npos);
    EXPECT_NE(message(sim->set_instance_active(6, false)).find("instance 6"), std::string::npos);
    std::vector<ForceField> many(17);
    EXPECT_NE(message(sim->set_force_fields(many)).find("at most 16"), std::string::npos);
    std::vector<ForceField> negative(1);
    negative[0].radius = -2.0;
    EXPECT_NE(message(sim->set_force_fields(negative)).find("radius"), std::string::npos);
    negative[0].radius = 1.0;
    negative[0].center.y = std::nan("");
    EXPECT_NE(message(sim->set_force_fields(negative)).find("force field 0"), std::string::npos);
    Wind wind = sim->wind();
    wind.strength = std::nan("");
    EXPECT_NE(message(sim->set_wind(wind)).find("strength"), std::string::npos);
    wind = sim->wind();
    wind.turbulence = 3.0;
    EXPECT_NE(message(sim->set_wind(wind)).find("turbulence"), std::string::npos);
    wind = sim->wind();
    wind.direction = {0, 0, 0};
    EXPECT_NE(message(sim->set_wind(wind)).find("direction"), std::string::npos);
    const uint64_t twice[] = {1, 1};
    EXPECT_NE(message(sim->remove_instances(twice)).find("twice"), std::string::npos);
    const uint64_t missing[] = {0, 40};
    EXPECT_NE(message(sim->remove_instances(missing)).find("instance 40"), std::string::npos);
    const uint64_t all[] = {0, 1, 2, 3, 4, 5};
    EXPECT_FALSE(sim->remove_instances(all).ok());
    const Instance unknown[] = {{7, {0, 0, 0}, 0.0}};
    EXPECT_NE(message(sim->add_instances(unknown)).find("model index 7"), std::string::npos);
    Instance nan_origin{0, {std::nan(""), 0, 0}, 0.0};
    EXPECT_NE(message(sim->add_instances({&nan_origin, 1})).find("origin"), std::string::npos);
    EXPECT_EQ(sim->instance_count(), 6u);
    EXPECT_TRUE(sim->force_fields().empty());
    EXPECT_EQ(sim->wind().strength, 3.0);
    ASSERT_TRUE(sim->step(15).ok());
    ASSERT_TRUE(twin->step(15).ok());
    EXPECT_EQ(read(*sim, Output::node_positions), read(*twin, Output::node_positions));
}

TEST_P(LiveControl, WindChangeIsPhaseContinuous) {
    // Re-setting the wind in force moves the clock's base but not tau: the run goes on as one
    // without the call (up to the rounding of tau_b + (f dt) k against (f dt) (n - 1)).
    SimulationConfig config;
    config.wind.strength = 4.0;
    std::string skip;
    auto a = test::create_simulation_or_skip(mixed_scene(), config, GetParam(), skip);
    if (!skip.empty()) GTEST_SKIP() << skip;
    auto b = test::create_simulation_or_skip(mixed_scene(), config, GetParam(), skip);
    ASSERT_TRUE(a->step(37).ok());
    ASSERT_TRUE(b->step(37).ok());
    ASSERT_TRUE(b->set_wind(b->wind()).ok());  // same wind, re-set: nothing changes
    ASSERT_TRUE(a->step(50).ok());
    ASSERT_TRUE(b->step(50).ok());
    EXPECT_LE(test::max_abs_difference(read(*a, Output::node_positions), read(*b, Output::node_positions)), 1e-6);
}

INSTANTIATE_TEST_SUITE_P(Backends, LiveControl,
                         ::testing::Values(BackendKind::cpu64, BackendKind::cpu, BackendKind::vulkan,
                                           BackendKind::cuda),
                         test::BackendTestName());

}  // namespace
}  // namespace hmsm
