// The coupled dynamics' articulated exchange (docs/model.md 3.13): the two sweeps solve the
// linearized tree's implicit step exactly (against a dense solve with the mass matrix of the
// linearized links), a released preset loses energy at every time step size, levels keep the
// folded bodies and scale their inertia by their own sway, and the option is refused where it
// does not run (the split rod's sway:
// coupled_links_test.cpp).
#include "simulation_access.h"
#include "test_trees.h"

#include "common/articulated_math.h"
#include "model/articulated_constants.h"
#include "model/linearized_links.h"

#include <hmsm/generator.h>
#include <hmsm/simulation.h>

#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <optional>
#include <random>
#include <string>

using namespace hmsm;

namespace {

constexpr uint32_t kRecord = 4 * HMSM_CHAIN_ARTICULATED_VEC4S;

/// Solves a x = b (dense, row-major n x n) by Gaussian elimination with partial pivoting.
std::vector<double> solve(std::vector<double> a, std::vector<double> b) {
    const size_t n = b.size();
    for (size_t col = 0; col < n; ++col) {
        size_t pivot = col;
        for (size_t r = col + 1; r < n; ++r)
            if (std::abs(a[r * n + col]) > std::abs(a[pivot * n + col])) pivot = r;
        for (size_t k = 0; k < n; ++k) std::swap(a[col * n + k], a[pivot * n + k]);
        std::swap(b[col], b[pivot]);
        for (size_t r = col + 1; r < n; ++r) {
            const double f = a[r * n + col] / a[col * n + col];
            for (size_t k = col; k < n; ++k) a[r * n + k] -= f * a[col * n + k];
            b[r] -= f * b[col];
        }
    }
    std::vector<double> x(n);
    for (size_t r = n; r-- > 0;) {
        double s = b[r];
        for (size_t k = r + 1; k < n; ++k) s -= a[r * n + k] * x[k];
        x[r] = s / a[r * n + r];
    }
    return x;
}

ModelOptions articulated_options() {
    ModelOptions options;
    options.dynamics = Dynamics::coupled;
    options.exchange = Exchange::articulated;
    return options;
}

/// A preset and its hierarchy under the articulated exchange for `parameters`.
struct ArticulatedPreset {
    TreeModel tree;
    Hierarchy hierarchy;
};
std::optional<ArticulatedPreset> articulated_preset(const char* name, const Parameters& parameters) {
    auto tree = generate_preset(name);
    EXPECT_TRUE(tree.ok()) << name;
    if (!tree.ok()) return std::nullopt;
    auto h = build_hierarchy(*tree, articulated_options(), parameters);
    EXPECT_TRUE(h.ok()) << name << ": " << h.status().message();
    if (!h.ok()) return std::nullopt;
    return ArticulatedPreset{std::move(*tree), std::move(*h)};
}

/// The lower of the tree's sway frequencies along the model's x and z (Hz): Rayleigh's quotient
/// with the static deflection q = K^-1 F under a uniform acceleration F, by the dense links.
double rayleigh_sway_hz(const detail::LinearizedLinks& links) {
    double lowest = 0.0;
    for (const glm::dvec3 along : {glm::dvec3(1, 0, 0), glm::dvec3(0, 0, 1)}) {
        const std::vector<double> f = detail::uniform_load(links, along);
        std::vector<double> q(f.size()), mq;
        for (size_t j = 0; j < f.size(); ++j) q[j] = f[j] / links.links[j / 2].stiffness[j % 2];
        detail::link_mass_times(links, q, mq);
        double work = 0.0, kinetic = 0.0;
        for (size_t j = 0; j < f.size(); ++j) {
            work += q[j] * f[j];
            kinetic += q[j] * mq[j];
        }
        const double hz = std::sqrt(work / kinetic) / (2 * std::numbers::pi);
        lowest = lowest == 0.0 ? hz : std::min(lowest, hz);
    }
    return lowest;
}

}  // namespace

// The whole tree's sway frequency of the records' inertia scale is Rayleigh's of the dense
// links (paper-1: 1.19 Hz, its fundamental mode's 1.19, docs/model.md 3.13).
TEST(ArticulatedExchange, SwayFrequencyIsTheLinkedTreesRayleighQuotient) {
    for (const char* preset : {"paper-1", "paper-5"}) {
        Parameters parameters;
        const auto built = articulated_preset(preset, parameters);
        ASSERT_TRUE(built);
        const TreeModel* tree = &built->tree;
        const Hierarchy* h = &built->hierarchy;
        const double dense = rayleigh_sway_hz(detail::linearize_links(*tree, *h, parameters));
        EXPECT_NEAR(detail::whole_tree_sway_hz(*h), dense, 1e-9 * dense) << preset;
        if (std::string(preset) == "paper-1") EXPECT_NEAR(dense, 1.19, 0.01);
    }
    // The scale: (x / tan x)^2 with x = pi f dt, capped at x = 1/2; 1 for a tree that does not sway.
    const double x = std::numbers::pi * 1.2 / 30.0;
    EXPECT_NEAR(detail::articulated_inertia_scale(1.2, 1.0 / 30.0), std::pow(x / std::tan(x), 2), 1e-15);
    EXPECT_EQ(detail::articulated_inertia_scale(50.0, 1.0 / 30.0), std::pow(0.5 / std::tan(0.5), 2));
    EXPECT_EQ(detail::articulated_inertia_scale(0.0, 1.0 / 30.0), 1.0);
}

// One step from a random state under random impulses: the sweeps' change of rate dV equals the
// solution of (M + dt Theta D + dt^2 Theta^2 K) dV = b + J^T f, with M assembled column by column
// from the linearized links (model frame, absolute poses), b = -dt K S - (dt D + Theta dt^2 K) V
// - the aerodynamic impulse, and J^T f each chain's own impulse (about its joint, in its frame)
// as generalized forces on its joint and every joint below it.
TEST(ArticulatedExchange, SweepsSolveTheLinearizedStepExactly) {
    Parameters parameters;
    parameters.dt = 1.0 / 45.0;  // some joints resolved (theta 1/2), some not (theta up to 1)
    const auto built = articulated_preset("paper-5", parameters);
    ASSERT_TRUE(built);
    const TreeModel* tree = &built->tree;
    const Hierarchy* h = &built->hierarchy;
    const size_t chains = h->chains.size(), n = 2 * chains;
    std::vector<double> records;
    detail::append_articulated_records(*h, parameters.dt, records);
    ASSERT_EQ(records.size(), chains * kRecord);

    std::mt19937_64 random(7);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    std::vector<double> angle(n), rate(n), impulse(chains * 8);
    for (double& v : angle) v = 0.05 * unit(random);
    for (double& v : rate) v = 0.3 * unit(random);
    for (size_t c = 0; c < chains; ++c)
        for (int i = 0; i < 8; ++i) impulse[8 * c + size_t(i)] = (i < 6 ? 0.5 : 0.02) * unit(random);

    // The sweeps, as the CPU backend runs them.
    std::vector<std::array<double, 6>> passed(chains), motion(chains);
    std::vector<std::array<double, 2>> free_rate(chains);
    std::vector<double> swept(n);
    for (size_t j = chains; j-- > 0;) {
        const double* r = &records[j * kRecord];
        double p[6] = {};
        for (size_t k = size_t(r[42]); k < size_t(r[42] + r[43]); ++k)
            for (int i = 0; i < 6; ++i) p[i] += passed[k][size_t(i)];
        detail::articulated_up(r, &angle[2 * j], &rate[2 * j], &impulse[8 * j], p, free_rate[j].data(), passed[j].data());
    }
    for (size_t j = 0; j < chains; ++j) {
        const int32_t parent = h->chains[j].parent;
        detail::articulated_down(&records[j * kRecord], parent >= 0 ? motion[size_t(parent)].data() : nullptr,
                                 free_rate[j].data(), &swept[2 * j], motion[j].data());
    }

    // The dense step, its inertia scaled as the records' (the fundamental's frequency from the
    // linearized links' static deflection under a uniform lateral load).
    const detail::LinearizedLinks links = detail::linearize_links(*tree, *h, parameters);
    const double scale = detail::articulated_inertia_scale(rayleigh_sway_hz(links), parameters.dt);
    EXPECT_LT(scale, 1.0);
    std::vector<double> a(n * n), b(n, 0.0), e(n), column;
    for (size_t j = 0; j < n; ++j) {
        std::fill(e.begin(), e.end(), 0.0);
        e[j] = 1.0;
        detail::link_mass_times(links, e, column);
        for (size_t i = 0; i < n; ++i) a[i * n + j] = scale * column[i];
    }
    const double dt = parameters.dt;
    for (size_t c = 0; c < chains; ++c) {
        const ChainDynamics& d = h->chains[c].dynamics;
        for (int ax = 0; ax < 2; ++ax) {
            const size_t i = 2 * c + size_t(ax);
            const double theta = detail::articulated_theta(d.frequency[ax], dt);
            const double damping = 2.0 * parameters.structural_damping * std::sqrt(d.stiffness[ax] * d.rigid_inertia[ax]);
            a[i * n + i] += theta * dt * damping + theta * theta * dt * dt * d.stiffness[ax];
            b[i] = -dt * d.stiffness[ax] * angle[i] - (dt * damping + theta * dt * dt * d.stiffness[ax]) * rate[i] -
                   impulse[8 * c + 6 + size_t(ax)];
        }
    }
    for (size_t k = 0; k < chains; ++k) {
        // Chain k's impulse in the model frame, about the origin.
        const glm::dmat3 frame(h->chains[k].frame);
        const glm::dvec3 pivot = links.links[k].pivot;
        const glm::dvec3 force = frame * glm::dvec3(impulse[8 * k + 3], impulse[8 * k + 4], impulse[8 * k + 5]);
        const glm::dvec3 moment =
            frame * glm::dvec3(impulse[8 * k], impulse[8 * k + 1], impulse[8 * k + 2]) + glm::cross(pivot, force);
        for (int32_t c = int32_t(k); c >= 0; c = h->chains[size_t(c)].parent)
            for (int ax = 0; ax < 2; ++ax) {
                const auto& link = links.links[size_t(c)];
                const glm::dvec3& u = link.axis[size_t(ax)];
                b[2 * size_t(c) + size_t(ax)] += glm::dot(u, moment) + glm::dot(glm::cross(link.pivot, u), force);
            }
    }
    const std::vector<double> dense = solve(a, b);
    double largest = 0.0, worst = 0.0;
    for (size_t i = 0; i < n; ++i) {
        largest = std::max(largest, std::abs(dense[i]));
        worst = std::max(worst, std::abs(swept[i] - dense[i]));
    }
    EXPECT_GT(largest, 1e-3);
    EXPECT_LT(worst, 1e-9 * largest) << chains << " chains";
}

namespace {

/// E = V^T M V / 2 + sum K S^2 / 2 of the linearized links at the simulation's angles and rates.
double joint_energy(const detail::LinearizedLinks& links, const std::vector<double>& state) {
    const size_t n = links.joints();
    std::vector<double> rate(n), mv;
    double potential = 0.0;
    for (size_t c = 0; c < links.links.size(); ++c)
        for (size_t a = 0; a < 2; ++a) {
            rate[2 * c + a] = state[4 * c + 2 + a];
            potential += 0.5 * links.links[c].stiffness[a] * state[4 * c + a] * state[4 * c + a];
        }
    detail::link_mass_times(links, rate, mv);
    double kinetic = 0.0;
    for (size_t i = 0; i < n; ++i) kinetic += 0.5 * rate[i] * mv[i];
    return kinetic + potential;
}

}  // namespace

// The device sweeps take an instance depth by depth, each depth the range of chains its records
// name (scalars 44 and 45): every chain lies in its own range, the ranges follow one another
// from the trunk to the last chain, a range holds one depth, and a chain's parent lies in the
// range before its own, so that a barrier after each range orders every parent and child.
TEST(ArticulatedExchange, RecordsNameEachDepthAsARange) {
    for (const char* preset : {"paper-1", "paper-5"}) {
        Parameters parameters;
        const auto built = articulated_preset(preset, parameters);
        ASSERT_TRUE(built);
        const Hierarchy* h = &built->hierarchy;
        std::vector<double> records;
        detail::append_articulated_records(*h, parameters.dt, records);
        const size_t chains = h->chains.size();
        std::vector<size_t> begin(chains), end(chains);
        for (size_t c = 0; c < chains; ++c) {
            begin[c] = size_t(records[c * kRecord + 44]);
            end[c] = size_t(records[c * kRecord + 45]);
            ASSERT_LE(begin[c], c) << preset << " chain " << c;
            ASSERT_LT(c, end[c]) << preset << " chain " << c;
        }
        EXPECT_EQ(begin[0], 0u);
        EXPECT_EQ(end[0], 1u) << "the trunk is a depth of its own";
        size_t depths = 0;
        for (size_t first = 0; first < chains; first = end[first], ++depths) {
            for (size_t c = first; c < end[first]; ++c) {
                EXPECT_EQ(begin[c], first) << preset << " chain " << c;
                EXPECT_EQ(end[c], end[first]) << preset << " chain " << c;
                if (c == 0) continue;
                const size_t parent = size_t(h->chains[c].parent);
                EXPECT_EQ(end[parent], first) << preset << " chain " << c << "'s parent " << parent;
            }
        }
        EXPECT_GE(depths, 3u) << preset;
    }
}

// Bent by a wind and released, a preset's joints lose energy at every step, whatever the step
// size, from steps that resolve every sway to steps far too long for its twigs: the step is
// implicit over the whole tree, and no explicit coupling feeds energy back.
TEST(ArticulatedExchange, ReleasedPresetLosesEnergyAtEveryStepSize) {
    for (const char* preset : {"paper-1", "paper-5"}) {
        auto tree = generate_preset(preset);
        ASSERT_TRUE(tree.ok());
        for (const double dt : {1.0 / 30.0, 1.0 / 240.0}) {
            SimulationConfig config = test::coupled_config(BackendKind::cpu64, dt);
            config.model.exchange = Exchange::articulated;
            config.wind.profile = WindProfile::constant;
            config.wind.strength = 4.0;
            auto sim = Simulation::create(single_tree_scene(*tree), config);
            ASSERT_TRUE(sim.ok()) << sim.status().message();
            auto h = build_hierarchy(*tree, config.model, config.parameters);
            ASSERT_TRUE(h.ok());
            const detail::LinearizedLinks links = detail::linearize_links(*tree, *h, config.parameters);
            ASSERT_TRUE((*sim)->step(uint32_t(std::lround(3.0 / dt))).ok());
            Wind calm = config.wind;
            calm.profile = WindProfile::none;
            ASSERT_TRUE((*sim)->set_wind(calm).ok());
            const double released = joint_energy(links, test::read_output(**sim, Output::chain_angles));
            double last = released;
            int rises = 0;
            const int steps = int(std::lround(8.0 / dt));
            for (int k = 0; k < steps; ++k) {
                ASSERT_TRUE((*sim)->step(1).ok());
                const double e = joint_energy(links, test::read_output(**sim, Output::chain_angles));
                if (e > last * (1.0 + 1e-9) + 1e-12 * released) ++rises;
                last = e;
            }
            std::printf("%s at dt 1/%.0f: energy %.4g J at the release, %.4g J 8 s later\n", preset, 1.0 / dt, released,
                        last);
            EXPECT_GT(released, 0.0);
            EXPECT_EQ(rises, 0) << preset << " at dt 1/" << 1.0 / dt;
            EXPECT_LT(last, 0.25 * released) << preset << " at dt 1/" << 1.0 / dt;
        }
    }
}

// Under the paper's dynamics, or as an unknown value, creation refuses the exchange with a
// message naming it; under the coupled dynamics every backend runs it.
TEST(ArticulatedExchange, RefusedOutsideTheCoupledDynamics) {
    const Scene scene = single_tree_scene(test::rod());
    SimulationConfig config = test::coupled_config();
    config.model.exchange = Exchange::articulated;
    config.model.dynamics = Dynamics::paper;
    auto paper = Simulation::create(scene, config);
    ASSERT_FALSE(paper.ok());
    EXPECT_NE(paper.status().message().find("exchange articulated needs dynamics coupled"), std::string::npos)
        << paper.status().message();
    config.model.dynamics = Dynamics::coupled;
    config.model.exchange = static_cast<Exchange>(7);
    auto unknown = Simulation::create(scene, config);
    ASSERT_FALSE(unknown.ok());
    EXPECT_NE(unknown.status().message().find("exchange 7"), std::string::npos) << unknown.status().message();
    config.model.exchange = Exchange::articulated;
    for (BackendKind kind : {BackendKind::cpu, BackendKind::cpu64, BackendKind::cpu_parallel}) {
        config.backend = kind;
        EXPECT_TRUE(Simulation::create(scene, config).ok()) << to_string(kind);
    }
}

// A level of detail folds chains into the chain that keeps them: under the exchange each kept
// chain's body takes the folded bodies rigidly, so a level keeps the tree's mass, its first mass
// moment and its inertia about the root; and a forest that switches levels runs.
TEST(ArticulatedExchange, LevelsKeepTheFoldedBodies) {
    auto tree = generate_preset("paper-5");
    ASSERT_TRUE(tree.ok());
    const ModelOptions options = articulated_options();
    Parameters parameters;
    auto full = build_hierarchy(*tree, options, parameters);
    ASSERT_TRUE(full.ok());
    // The whole body about the root, in the tree's frame, by chains' absolute frames and joints.
    struct Whole {
        double mass = 0;
        glm::dvec3 moment{0.0};
        glm::dmat3 inertia{0.0};
    };
    auto whole = [&](const Hierarchy& h) {
        Whole w;
        for (const Chain& chain : h.chains) {
            const ChainDynamics& d = chain.dynamics;
            const glm::dmat3 b(chain.frame);
            const glm::dvec3 p = tree->nodes[size_t(chain.attach_node)].position - tree->nodes[0].position;
            const glm::dvec3 hm = b * glm::dvec3(d.own_mass_moment);
            w.mass += d.mass;
            w.moment += d.mass * p + hm;
            w.inertia += b * glm::dmat3(d.own_inertia) * glm::transpose(b) +
                         d.mass * (glm::dot(p, p) * glm::dmat3(1.0) - glm::outerProduct(p, p)) +
                         2.0 * glm::dot(p, hm) * glm::dmat3(1.0) - glm::outerProduct(p, hm) - glm::outerProduct(hm, p);
        }
        return w;
    };
    const Whole reference = whole(*full);
    for (int32_t budget : {64, 16, 1}) {
        auto level = build_level(*tree, *full, parameters, budget);
        ASSERT_TRUE(level.ok()) << level.status().message();
        ASSERT_LT(level->joint_count(), int32_t(full->chains.size()));
        const Whole folded = whole(level->hierarchy);
        EXPECT_NEAR(folded.mass, reference.mass, 1e-9 * reference.mass) << budget;
        for (int i = 0; i < 3; ++i) {
            EXPECT_NEAR(folded.moment[i], reference.moment[i], 1e-9 * reference.mass * 10) << budget;
            for (int j = 0; j < 3; ++j)
                EXPECT_NEAR(folded.inertia[i][j], reference.inertia[i][j], 1e-9 * reference.inertia[1][1] + 1e-9)
                    << budget;
        }
    }
    // A forest on levels, switching: it runs on, and cpu agrees with cpu64.
    Scene scene = single_tree_scene(*tree);
    scene.lod_budgets = {{64, 16}};
    for (int k = 1; k < 3; ++k) {
        Instance more = scene.instances[0];
        more.origin = {15.0 * k, 0.0, 0.0};
        more.level = uint64_t(k);
        scene.instances.push_back(more);
    }
    SimulationConfig config = test::coupled_config(BackendKind::cpu64);
    config.model.exchange = Exchange::articulated;
    config.wind.profile = WindProfile::turbulent;
    config.wind.strength = 3.0;
    auto oracle = Simulation::create(scene, config);
    ASSERT_TRUE(oracle.ok()) << oracle.status().message();
    config.backend = BackendKind::cpu;
    auto tested = Simulation::create(scene, config);
    ASSERT_TRUE(tested.ok()) << tested.status().message();
    // Two switches mid-run: the carried state goes on under the other level's sweeps.
    for (Simulation* sim : {oracle->get(), tested->get()}) {
        ASSERT_TRUE(sim->step(150).ok());
        ASSERT_TRUE(sim->set_instance_lod(sim->instance_ids()[0], 2).ok());
        ASSERT_TRUE(sim->set_instance_lod(sim->instance_ids()[2], 0).ok());
        ASSERT_TRUE(sim->step(150).ok());
    }
    const auto expected = test::read_output(**oracle, Output::node_positions);
    const auto actual = test::read_output(**tested, Output::node_positions);
    double scale = 0;
    for (double v : expected) scale = std::max(scale, std::abs(v));
    EXPECT_TRUE(test::all_finite(actual));
    EXPECT_LT(test::max_abs_difference(actual, expected), 1e-5 * scale);
}

// Each level is a model of its own: its records' inertia scale comes from its own whole-tree
// sway frequency, not from the full model's (the levels' frequencies differ, so records made
// with one frequency for all would not match).
TEST(ArticulatedExchange, EachLevelScalesItsInertiaByItsOwnSway) {
    auto tree = generate_preset("paper-5");
    ASSERT_TRUE(tree.ok());
    Scene scene = single_tree_scene(*tree);
    scene.lod_budgets = {{64, 16}};
    SimulationConfig config = test::coupled_config(BackendKind::cpu64, 1.0 / 30.0);
    config.model.exchange = Exchange::articulated;
    auto sim = Simulation::create(scene, config);
    ASSERT_TRUE(sim.ok()) << sim.status().message();
    const detail::SceneData& d = detail::scene_data_of(**sim);
    const std::vector<Hierarchy>& levels = detail::SimulationAccess::impl(**sim).hierarchies_;
    ASSERT_EQ(levels.size(), 3u);
    ASSERT_EQ(d.models.size(), levels.size());
    std::vector<double> hz;
    for (size_t m = 0; m < levels.size(); ++m) {
        SCOPED_TRACE("level " + std::to_string(m));
        hz.push_back(detail::whole_tree_sway_hz(levels[m]));
        std::vector<double> own;
        detail::append_articulated_records(levels[m], d.dt, own);
        ASSERT_EQ(own.size(), size_t(d.models[m].chain_count) * kRecord);
        const double* flat = d.chain_articulated.data() + size_t(d.models[m].chain_begin) * kRecord;
        for (size_t k = 0; k < own.size(); ++k) ASSERT_EQ(flat[k], own[k]) << "scalar " << k;
        EXPECT_LT(detail::articulated_inertia_scale(hz[m], d.dt), 1.0);
    }
    EXPECT_NE(hz[1], hz[0]);
    EXPECT_NE(hz[2], hz[0]);
    EXPECT_NEAR(hz[1], hz[0], 0.05 * hz[0]) << "a level keeps the full model's sway within 5 %";
}
