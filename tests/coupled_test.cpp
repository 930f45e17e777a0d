// The coupled dynamics (docs/model.md 3.13): constants against the analytic cantilever, the
// free sway of a rod, energy decay, dt independence, the float backends against cpu64, and bad
// materials refused through the API, the C ABI and the command line.
#include "cli_fixture.h"
#include "simulation_access.h"
#include "test_trees.h"
#include "tree_response.h"

#include "backend.h"
#include "model/coupled_constants.h"

#include <hmsm/hmsm_c.h>

#include <nlohmann/json.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

using namespace hmsm;


// The tapered-beam constants of a uniform rod: K = 3 E J / L, the Rayleigh frequency within 1%
// of 1.8751^2 / (2 pi) sqrt(E J / (mu L^4)), the wind moment along the rod's axis.
// (One segment: a chain of one member is never split into links.)
TEST(CoupledConstants, UniformRodMatchesTheAnalyticCantilever) {
    const double L = 5.0, r = 0.2;
    ModelOptions options;
    options.dynamics = Dynamics::coupled;
    Parameters parameters;
    auto h = build_hierarchy(test::rod(1, L, r), options, parameters);
    ASSERT_TRUE(h.ok()) << h.status().message();
    ASSERT_EQ(h->chains.size(), 1u);
    const ChainDynamics& d = h->chains[0].dynamics;
    const Material& m = parameters.material;
    const double J = std::numbers::pi * std::pow(r, 4) / 4.0;
    EXPECT_NEAR(d.beam_stiffness, 3.0 * m.modulus * J / L, 1e-2 * d.beam_stiffness);
    const double f0 = detail::uniform_cantilever_frequency(L, r, m);
    for (int a = 0; a < 2; ++a) {
        EXPECT_NEAR(d.frequency[a], f0, 0.01 * f0) << "axis " << a;
        EXPECT_NEAR(std::sqrt(d.stiffness[a] / d.inertia[a]) / (2 * std::numbers::pi), d.frequency[a], 1e-9 * f0);
    }
    const double mass = m.density * std::numbers::pi * r * r * L;
    EXPECT_NEAR(d.mass, mass, 1e-9 * mass);
    EXPECT_NEAR(d.inertia[0], mass * L * L / 3.0, 1e-6 * d.inertia[0]);
    const double drag = parameters.wood_drag_coefficient * 2 * r * L;
    EXPECT_NEAR(d.wind_moment.y, drag * L / 2, 1e-9);
    EXPECT_NEAR(d.wind_moment.x, 0.0, 1e-12);
    EXPECT_NEAR(d.wind_moment.z, 0.0, 1e-12);
}

// Children are one contiguous id range, their subtree masses add up, and a crown lowers the
// trunk's frequency (its inertia and load are the trunk's too).
TEST(CoupledConstants, ChildrenAreLumpedIntoTheirParent) {
    ModelOptions options;
    options.dynamics = Dynamics::coupled;
    const TreeModel tree = test::small_tree();
    auto h = build_hierarchy(tree, options);
    ASSERT_TRUE(h.ok()) << h.status().message();
    double total = 0.0;
    for (size_t c = 0; c < h->chains.size(); ++c) {
        const ChainDynamics& d = h->chains[c].dynamics;
        total += d.mass;
        double sum = d.mass;
        for (int32_t k = d.first_child; k < d.first_child + d.child_count; ++k) {
            EXPECT_EQ(h->chains[k].parent, int32_t(c));
            sum += h->chains[k].dynamics.subtree_mass;
        }
        EXPECT_NEAR(d.subtree_mass, sum, 1e-12 * sum);
        EXPECT_GT(d.inertia[0], 0.0);
    }
    EXPECT_NEAR(h->chains[0].dynamics.subtree_mass, total, 1e-12 * total);
    Parameters leafless;
    leafless.foliage.on = false;
    auto bare = build_hierarchy(tree, options, leafless);
    ASSERT_TRUE(bare.ok());
    EXPECT_LT(bare->chains[0].dynamics.subtree_mass, h->chains[0].dynamics.subtree_mass);
}

// A uniform rod released from its wind-bent shape sways at the cantilever's first frequency.
TEST(Coupled, UniformRodSwaysAtTheCantileverFrequency) {
    const double L = 5.0, r = 0.2;
    SimulationConfig config = test::coupled_config();
    config.wind.profile = WindProfile::constant;
    config.wind.strength = 100.0;
    auto sim = Simulation::create(single_tree_scene(test::rod(4, L, r)), config);
    ASSERT_TRUE(sim.ok()) << sim.status().message();
    const std::vector<double> theta_z = test::released_record(**sim, 120, 240, [](const Simulation& s) {
        return test::read_output(s, Output::chain_angles)[1];
    });
    ASSERT_EQ(theta_z.size(), 240u);
    const double f0 = detail::uniform_cantilever_frequency(L, r, config.parameters.material);
    EXPECT_NEAR(cli::decay_frequency(theta_z, config.parameters.dt), f0, 0.03 * f0);
}

// Without wind, a swaying tree comes to rest: the largest |angle| of each half second shrinks.
TEST(Coupled, MotionDecaysWithoutWind) {
    SimulationConfig config = test::coupled_config();
    config.wind.profile = WindProfile::constant;
    config.wind.strength = 20.0;
    auto sim = Simulation::create(single_tree_scene(test::small_tree()), config);
    ASSERT_TRUE(sim.ok()) << sim.status().message();
    const std::vector<double> largest = test::released_record(**sim, 60, 480, [](const Simulation& s) {
        double peak = 0.0;
        for (double v : test::read_output(s, Output::chain_angles)) peak = std::max(peak, std::abs(v));
        return peak;
    });
    ASSERT_EQ(largest.size(), 480u);
    std::vector<double> peaks;  // per half second
    for (size_t window = 0; window < 8; ++window)
        peaks.push_back(*std::max_element(largest.begin() + std::ptrdiff_t(60 * window),
                                          largest.begin() + std::ptrdiff_t(60 * (window + 1))));
    ASSERT_GT(peaks.front(), 0.0);
    for (size_t w = 1; w < peaks.size(); ++w) EXPECT_LT(peaks[w], peaks[w - 1]) << "window " << w;
    EXPECT_LT(peaks.back(), 0.1 * peaks.front());
}

/// The displacement of node `node` from rest, every 1/30 s for three seconds, at time step dt.
std::vector<double> tip_path(const TreeModel& tree, int node, double dt, const Wind& wind) {
    SimulationConfig config = test::coupled_config();
    config.parameters.dt = dt;
    config.wind = wind;
    auto sim = Simulation::create(single_tree_scene(tree), config);
    EXPECT_TRUE(sim.ok()) << sim.status().message();
    std::vector<double> path;
    if (!sim.ok()) return path;
    const int per_frame = int(std::lround((1.0 / 30.0) / dt));
    for (int frame = 0; frame < 90; ++frame) {
        EXPECT_TRUE((*sim)->step(per_frame).ok());
        const auto xyz = test::read_output(**sim, Output::node_positions);
        for (int k = 0; k < 3; ++k) path.push_back(xyz[3 * node + k] - tree.nodes[node].position[k]);
    }
    return path;
}

/// max |a - b| over the largest |a|.
double relative_difference(const std::vector<double>& a, const std::vector<double>& b) {
    double motion = 0.0;
    for (double v : a) motion = std::max(motion, std::abs(v));
    EXPECT_GT(motion, 0.0);
    return test::max_abs_difference(a, b) / motion;
}

// The exact step makes an isolated chain's sway independent of dt (a rod of one segment, one
// link); in a tree, what is held over a step (the wind, the children's loads) converges to
// first order: the tip's path at dt = 1/60 and 1/30 stays close to the one at 1/240.
TEST(Coupled, TipMotionIsCloseAcrossTimeSteps) {
    Wind steady;
    steady.profile = WindProfile::constant;
    steady.strength = 50.0;
    const TreeModel rod = test::rod(1, 5.0, 0.2);
    const auto fine_rod = tip_path(rod, 1, 1.0 / 240.0, steady);
    for (double dt : {1.0 / 60.0, 1.0 / 30.0}) EXPECT_LT(relative_difference(fine_rod, tip_path(rod, 1, dt, steady)), 0.01);

    Wind gusts;
    gusts.profile = WindProfile::y2;
    gusts.frequency = 0.5;
    gusts.strength = 20.0;
    const TreeModel tree = test::small_tree();
    const auto fine = tip_path(tree, 11, 1.0 / 240.0, gusts);
    const double at_60 = relative_difference(fine, tip_path(tree, 11, 1.0 / 60.0, gusts));
    const double at_30 = relative_difference(fine, tip_path(tree, 11, 1.0 / 30.0, gusts));
    EXPECT_LT(at_60, 0.15);
    EXPECT_LT(at_30, 0.3);
    EXPECT_LT(at_60, at_30);
}

// cpu and cpu-parallel (split into the smallest chunks) agree with cpu64 over 1,000 steps with
// live wind changes and force fields; cpu-parallel agrees with cpu bit for bit.
TEST(Coupled, FloatBackendsAgreeWithCpu64) {
    auto preset = generate_preset("paper-5");
    ASSERT_TRUE(preset.ok());
    auto grid = grid_scene(*preset, 3, 20.0, 1);
    ASSERT_TRUE(grid.ok());
    const Scene& scene = *grid;
    SimulationConfig config = test::coupled_config();
    config.wind.profile = WindProfile::turbulent;
    config.wind.strength = 4.0;
    std::vector<std::unique_ptr<Simulation>> sims;
    for (BackendKind kind : {BackendKind::cpu64, BackendKind::cpu}) {
        config.backend = kind;
        auto sim = Simulation::create(scene, config);
        ASSERT_TRUE(sim.ok()) << sim.status().message();
        sims.push_back(std::move(sim).value());
    }
    auto parallel_backend = detail::create_cpu_parallel_backend(3, 1);
    ASSERT_TRUE(parallel_backend.ok());
    auto parallel = detail::SimulationAccess::create(scene, config, std::move(parallel_backend).value());
    ASSERT_TRUE(parallel.ok()) << parallel.status().message();
    sims.push_back(std::move(parallel).value());

    ForceField push;
    push.center = {0.0, 6.0, 0.0};
    push.radius = 8.0;
    push.directional = {0.0, 0.0, 30.0};
    Wind gust = config.wind;
    gust.profile = WindProfile::y1;
    gust.strength = 9.0;
    gust.direction = {0.3, 0.0, 1.0};
    for (int phase = 0; phase < 4; ++phase) {
        for (auto& sim : sims) {
            if (phase == 1) ASSERT_TRUE(sim->set_wind(gust).ok());
            if (phase == 2) ASSERT_TRUE(sim->set_force_fields(std::span(&push, 1)).ok());
            if (phase == 3) ASSERT_TRUE(sim->set_force_fields({}).ok());
            ASSERT_TRUE(sim->step(250).ok());
        }
    }
    const auto oracle = test::read_output(*sims[0], Output::node_positions);
    const auto angles = test::read_output(*sims[0], Output::chain_angles);
    double scale = 0.0, swing = 0.0;
    for (double v : oracle) scale = std::max(scale, std::abs(v));
    for (size_t i = 0; i < angles.size(); i += 4) swing = std::max({swing, std::abs(angles[i]), std::abs(angles[i + 1])});
    ASSERT_GT(swing, 1e-4);
    for (size_t s = 1; s < sims.size(); ++s) {
        EXPECT_LT(test::max_abs_difference(test::read_output(*sims[s], Output::node_positions), oracle), 1e-5 * scale)
            << to_string(sims[s]->backend_kind());
    }
    std::vector<float> serial, threaded;
    ASSERT_TRUE(sims[1]->read(Output::chain_angles, serial).ok());
    ASSERT_TRUE(sims[2]->read(Output::chain_angles, threaded).ok());
    EXPECT_EQ(serial, threaded);
}

// The paper's dynamics is the default (tests/coupled_backends_test.cpp runs the coupled one on
// every backend and composition).
TEST(Coupled, PaperIsTheDefault) { EXPECT_EQ(ModelOptions{}.dynamics, Dynamics::paper); }

TEST(Coupled, BadMaterialsAreRefusedNamingTheValue) {
    const Scene scene = single_tree_scene(test::small_tree());
    struct Case {
        void (*set)(Parameters&);
        const char* fragment;
    };
    const Case cases[] = {
        {[](Parameters& p) { p.material.modulus = 9.0; }, "material.modulus = 9 is out of range"},
        {[](Parameters& p) { p.material.density = 0.9; }, "material.density = 0.9 is out of range"},
        {[](Parameters& p) { p.material.density = std::nan(""); }, "material.density = nan is not finite"},
        {[](Parameters& p) { p.foliage.mass_per_area = -1.0; }, "foliage.mass_per_area = -1"},
        {[](Parameters& p) { p.structural_damping = 1e9; }, "structural_damping = 1e+09"},
    };
    for (const Case& c : cases) {
        SimulationConfig config = test::coupled_config();
        c.set(config.parameters);
        auto sim = Simulation::create(scene, config);
        ASSERT_FALSE(sim.ok()) << c.fragment;
        EXPECT_EQ(sim.status().code(), ErrorCode::invalid_argument);
        EXPECT_NE(sim.status().message().find(c.fragment), std::string::npos) << sim.status().message();
    }
}

TEST(Coupled, BadMaterialsAreRefusedThroughTheCAbi) {
    hmsm_config config;
    ASSERT_EQ(HMSM_INIT(hmsm_config_init, &config), HMSM_OK);
    EXPECT_EQ(config.dynamics, HMSM_DYNAMICS_PAPER);
    EXPECT_EQ(config.coupled.modulus, Parameters{}.material.modulus);
    hmsm_tree* tree = nullptr;
    ASSERT_EQ(hmsm_tree_preset("paper-5", 0, &tree), HMSM_OK) << hmsm_status_message();
    hmsm_scene* scene = nullptr;
    ASSERT_EQ(hmsm_scene_create(&scene), HMSM_OK);
    ASSERT_EQ(hmsm_scene_add_model(scene, tree, "paper-5", nullptr), HMSM_OK) << hmsm_status_message();
    hmsm_instance instance;
    ASSERT_EQ(HMSM_INIT(hmsm_instance_init, &instance), HMSM_OK);
    ASSERT_EQ(hmsm_scene_add_instance(scene, &instance), HMSM_OK) << hmsm_status_message();
    config.backend = HMSM_BACKEND_CPU;
    config.dynamics = HMSM_DYNAMICS_COUPLED;
    config.coupled.modulus = -5.0;
    hmsm_simulation* sim = nullptr;
    EXPECT_EQ(hmsm_simulation_create(scene, &config, &sim), HMSM_INVALID_ARGUMENT);
    EXPECT_EQ(sim, nullptr);
    EXPECT_NE(std::string(hmsm_status_message()).find("material.modulus = -5"), std::string::npos)
        << hmsm_status_message();
    config.coupled.modulus = 9e9;
    config.dynamics = 7;
    EXPECT_EQ(hmsm_simulation_create(scene, &config, &sim), HMSM_INVALID_ARGUMENT);
    EXPECT_NE(std::string(hmsm_status_message()).find("config.dynamics: unknown value 7"), std::string::npos);
    config.dynamics = HMSM_DYNAMICS_COUPLED;
    ASSERT_EQ(hmsm_simulation_create(scene, &config, &sim), HMSM_OK) << hmsm_status_message();
    EXPECT_EQ(hmsm_simulation_step(sim, 10), HMSM_OK);
    hmsm_simulation_destroy(sim);
    hmsm_scene_destroy(scene);
    hmsm_tree_destroy(tree);
}

class CoupledCli : public test::CliFixture {};

TEST_F(CoupledCli, SimulatesAndRefusesBadMaterials) {
    const test::CliRun ok = run("simulate --tree " + path("small.json") + " --dynamics coupled --backend cpu --steps 30");
    EXPECT_EQ(ok.exit_code, 0) << ok.err;
    expect_bad_input("simulate --tree " + path("small.json") + " --dynamics coupled --modulus 9",
                     "material.modulus = 9 is out of range");
    expect_bad_input("simulate --tree " + path("small.json") + " --dynamics flexible", "--dynamics");
    // The articulated exchange; under paper, bad input.
    const test::CliRun articulated = run("simulate --tree " + path("small.json") +
                                         " --dynamics coupled --exchange articulated --backend cpu64 --steps 30");
    EXPECT_EQ(articulated.exit_code, 0) << articulated.err;
    expect_bad_input("simulate --tree " + path("small.json") + " --dynamics coupled --exchange loose", "--exchange");
    expect_bad_input("simulate --tree " + path("small.json") + " --exchange articulated",
                     "exchange articulated needs dynamics coupled");
}

// hmsm info --dynamics coupled: the trunk's constants as build_hierarchy computes them, and the
// range of the chains' frequencies; without it, no coupled section.
TEST_F(CoupledCli, InfoSummarizesTheCoupledConstants) {
    const test::CliRun r = run("info --preset paper-1 --json --dynamics coupled");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto info = nlohmann::json::parse(r.out);
    ASSERT_TRUE(info.contains("coupled")) << r.out;
    auto tree = generate_preset("paper-1");
    ASSERT_TRUE(tree.ok());
    ModelOptions options;
    options.dynamics = Dynamics::coupled;
    auto h = build_hierarchy(*tree, options, Parameters{});
    ASSERT_TRUE(h.ok()) << h.status().message();
    const ChainDynamics& trunk = h->chains.front().dynamics;
    const auto& t = info["coupled"]["trunk"];
    EXPECT_DOUBLE_EQ(t["frequency_hz"][0].get<double>(), trunk.frequency[0]);
    EXPECT_DOUBLE_EQ(t["subtree_mass_kg"].get<double>(), trunk.subtree_mass);
    EXPECT_DOUBLE_EQ(t["stiffness_n_m_per_rad"][1].get<double>(), trunk.stiffness[1]);
    EXPECT_DOUBLE_EQ(t["damping_n_m_s_per_rad"][0].get<double>(), trunk.damping[0]);
    EXPECT_GT(trunk.frequency[0], 0.0);
    EXPECT_LE(info["coupled"]["chain_frequency_min_hz"].get<double>(), trunk.frequency[0]);
    EXPECT_GE(info["coupled"]["chain_frequency_max_hz"].get<double>(), trunk.frequency[0]);
    const auto paper = nlohmann::json::parse(run("info --preset paper-1 --json").out);
    EXPECT_FALSE(paper.contains("coupled"));
    const test::CliRun text = run("info --preset paper-1 --dynamics coupled");
    ASSERT_EQ(text.exit_code, 0) << text.err;
    EXPECT_NE(text.out.find("coupled trunk"), std::string::npos) << text.out;
    expect_bad_input("info --preset paper-1 --dynamics flexible", "--dynamics");
}

// hmsm bench --dynamics coupled: per backend a one-tree and a joints-only forest row, each with
// the paper's and the coupled time per step (held and articulated), and their ratios in the table.
TEST_F(CoupledCli, BenchReportsCoupledBesidePaper) {
    const std::string file = path("bench.json");
    const test::CliRun r = run("bench --quick --no-progress --backends cpu --presets none --instances none "
                               "--joint-instances none --dynamics coupled --json " + file);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto document = nlohmann::json::parse(test::read_text(file));
    const auto& rows = document["dynamics"];
    ASSERT_EQ(rows.size(), 2u) << rows.dump();
    EXPECT_EQ(rows[0]["instances"], 1);
    EXPECT_EQ(rows[1]["instances"], 10);
    EXPECT_EQ(rows[1]["outputs"], "joints");
    for (const auto& row : rows) {
        ASSERT_FALSE(row.contains("failed")) << row.dump();
        EXPECT_GT(row["paper_ms"].get<double>(), 0.0);
        EXPECT_GT(row["coupled_ms"].get<double>(), 0.0);
        EXPECT_GT(row["articulated_ms"].get<double>(), 0.0);
    }
    EXPECT_NE(r.out.find("coupled / paper"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("articulated / paper"), std::string::npos) << r.out;
    expect_bad_input("bench --quick --no-progress --backends cpu --dynamics flexible", "--dynamics");
}
