// `hmsm simulate`'s wind, schedule and output flags (docs/model.md 5): --dump-chains, --trace,
// --dump-nodes formats (%.17g, the current instance list), turbulent wind and --wind-speed,
// --max-frequency, --wind-schedule, integers beyond their type, progress.
#include "cli_fixture.h"
#include "test_trees.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <sstream>

using namespace hmsm;
namespace fs = std::filesystem;

namespace {

using Rows = std::vector<std::vector<std::string>>;
using test::read_text;

class CliLive : public test::CliFixture {
protected:
    /// Header and rows of a CSV file.
    static Rows csv(const std::string& file, std::string& header) {
        std::ifstream in(file);
        std::getline(in, header);
        Rows rows;
        for (std::string line; std::getline(in, line);) {
            std::vector<std::string> cells;
            std::stringstream s(line);
            for (std::string cell; std::getline(s, cell, ',');) cells.push_back(cell);
            rows.push_back(cells);
        }
        return rows;
    }
    void write(const std::string& name, const std::string& content) { std::ofstream(path(name)) << content; }

    /// Bad input to a simulation that would otherwise write out.csv.
    void expect_bad(const std::string& args, const std::string& fragment) {
        expect_bad_input(args + " --dump-nodes " + path("out.csv"), fragment);
    }

    std::string simulate(const std::string& extra) const {
        return "simulate --tree " + path("small.json") + " --backend cpu64 " + extra;
    }
};

/// %.17g round trip: the text is the shortest exact rendering of the double it parses to.
void expect_round_trip(const std::string& cell) {
    const double v = std::strtod(cell.c_str(), nullptr);
    char again[64];
    std::snprintf(again, sizeof again, "%.17g", v);
    EXPECT_EQ(cell, again);
}

}  // namespace

TEST_F(CliLive, DumpChainsAndNodesMatchTheLibraryToTheLastBit) {
    ASSERT_EQ(run(simulate("--steps 25 --instances 3 --spacing 4 --dump-chains " + path("c.csv") + " --dump-nodes " +
                           path("n.csv"))).exit_code,
              0)
        << last_.err;
    std::string header;
    Rows chains = csv(path("c.csv"), header);
    EXPECT_EQ(header, "instance,chain,ox,oy,oz,r00,r10,r20,r01,r11,r21,r02,r12,r22");
    Rows nodes = csv(path("n.csv"), header);
    EXPECT_EQ(header, "instance,node,x,y,z");

    // The same run through the library.
    auto scene = grid_scene(test::small_tree(), 3, 4.0, 1);
    ASSERT_TRUE(scene.ok());
    SimulationConfig config;
    config.backend = BackendKind::cpu64;
    auto sim = Simulation::create(*scene, config);
    ASSERT_TRUE(sim.ok()) << sim.status().message();
    ASSERT_TRUE((*sim)->step(25).ok());
    std::vector<double> origins, rotations, xyz;
    ASSERT_TRUE((*sim)->read(Output::chain_origins, origins).ok());
    ASSERT_TRUE((*sim)->read(Output::chain_rotations, rotations).ok());
    ASSERT_TRUE((*sim)->read(Output::node_positions, xyz).ok());
    const size_t per_instance = (*sim)->hierarchy(0).chains.size();
    ASSERT_EQ(chains.size(), 3 * per_instance);
    for (size_t row = 0; row < chains.size(); ++row) {
        const auto& r = chains[row];
        ASSERT_EQ(r.size(), 14u);
        EXPECT_EQ(r[0], std::to_string(row / per_instance));
        EXPECT_EQ(r[1], std::to_string(row % per_instance));
        for (int k = 0; k < 3; ++k) EXPECT_EQ(std::strtod(r[2 + k].c_str(), nullptr), origins[3 * row + k]);
        for (int k = 0; k < 9; ++k)  // column by column: r00 r10 r20 r01 ...
            EXPECT_EQ(std::strtod(r[5 + k].c_str(), nullptr), rotations[9 * row + k]);
        for (size_t k = 2; k < 14; ++k) expect_round_trip(r[k]);
    }
    const size_t n = test::small_tree().nodes.size();
    ASSERT_EQ(nodes.size(), 3 * n);
    for (size_t row = 0; row < nodes.size(); ++row) {
        EXPECT_EQ(nodes[row][0], std::to_string(row / n));
        EXPECT_EQ(nodes[row][1], std::to_string(row % n));
        for (int k = 0; k < 3; ++k) {
            EXPECT_EQ(std::strtod(nodes[row][2 + k].c_str(), nullptr), xyz[3 * row + k]);
            expect_round_trip(nodes[row][2 + k]);
        }
    }
}

TEST_F(CliLive, TraceRowsEveryStepForTheListedNodesOfEveryInstance) {
    const TreeModel tree = test::small_tree();
    ASSERT_EQ(run(simulate("--steps 7 --instances 2 --trace " + path("t.csv") + " --trace-nodes 3,0 --dump-nodes " +
                           path("n.csv"))).exit_code,
              0)
        << last_.err;
    std::string header;
    Rows trace = csv(path("t.csv"), header);
    EXPECT_EQ(header, "step,instance,node,x,y,z");
    ASSERT_EQ(trace.size(), 7u * 2u * 2u);
    size_t row = 0;
    for (int step = 1; step <= 7; ++step)
        for (int instance = 0; instance < 2; ++instance)
            for (const char* node : {"3", "0"}) {
                EXPECT_EQ(trace[row][0], std::to_string(step));
                EXPECT_EQ(trace[row][1], std::to_string(instance));
                EXPECT_EQ(trace[row][2], node);
                for (int k = 3; k < 6; ++k) expect_round_trip(trace[row][k]);
                ++row;
            }
    // The last step's rows are the dump's rows for the same nodes.
    Rows nodes = csv(path("n.csv"), header);
    const size_t n = tree.nodes.size();
    for (size_t r = trace.size() - 4; r < trace.size(); ++r) {
        const size_t at = std::stoul(trace[r][1]) * n + std::stoul(trace[r][2]);
        for (int k = 0; k < 3; ++k) EXPECT_EQ(trace[r][3 + k], nodes[at][2 + k]);
    }
    // The traced node moves in the wind.
    EXPECT_NE(trace[0][3], trace[trace.size() - 4][3]);

    // top: the node with the highest rest y (lowest index on ties).
    uint32_t top = 0;
    for (uint32_t i = 1; i < tree.nodes.size(); ++i)
        if (tree.nodes[i].position.y > tree.nodes[top].position.y) top = i;
    ASSERT_EQ(run(simulate("--steps 3 --trace " + path("top.csv") + " --trace-nodes top")).exit_code, 0) << last_.err;
    Rows tops = csv(path("top.csv"), header);
    ASSERT_EQ(tops.size(), 3u);
    for (const auto& r : tops) EXPECT_EQ(r[2], std::to_string(top));
    // No steps: the header alone.
    ASSERT_EQ(run(simulate("--steps 0 --trace " + path("none.csv") + " --trace-nodes top")).exit_code, 0) << last_.err;
    EXPECT_EQ(read_text(path("none.csv")), "step,instance,node,x,y,z\n");
}

TEST_F(CliLive, TraceNodesMustExistInEveryModel) {
    const std::string n = std::to_string(test::small_tree().nodes.size());
    expect_bad(simulate("--steps 2 --trace " + path("t.csv") + " --trace-nodes 0," + n), "does not exist");
    EXPECT_FALSE(fs::exists(path("t.csv")));
    expect_bad(simulate("--steps 2 --trace " + path("t.csv") + " --trace-nodes 1,x"), "--trace-nodes");
    expect_bad(simulate("--steps 2 --trace " + path("t.csv") + " --trace-nodes 1,1"), "twice");
    expect_bad(simulate("--steps 2 --trace " + path("t.csv") + " --trace-nodes ''"), "--trace-nodes");
    expect_bad(simulate("--steps 2 --trace " + path("t.csv")), "--trace-nodes");
    expect_bad(simulate("--steps 2 --trace-nodes top"), "--trace");
}

TEST_F(CliLive, WindSpeedIsStrengthOfTheSquaredRatioToSixMetresPerSecond) {
    ASSERT_EQ(run(simulate("--steps 30 --wind constant --wind-speed 12 --dump-nodes " + path("a.csv"))).exit_code, 0)
        << last_.err;
    ASSERT_EQ(run(simulate("--steps 30 --wind constant --wind-strength 4 --dump-nodes " + path("b.csv"))).exit_code, 0)
        << last_.err;
    ASSERT_EQ(run(simulate("--steps 30 --wind constant --wind-strength 1 --dump-nodes " + path("c.csv"))).exit_code, 0)
        << last_.err;
    EXPECT_EQ(read_text(path("a.csv")), read_text(path("b.csv")));
    EXPECT_NE(read_text(path("a.csv")), read_text(path("c.csv")));
    expect_bad(simulate("--steps 2 --wind-speed 12 --wind-strength 4"), "--wind-speed");
    expect_bad(simulate("--steps 2 --wind-speed -1"), "--wind-speed");
    expect_bad(simulate("--steps 2 --wind-speed nan"), "--wind-speed");
}

TEST_F(CliLive, TurbulentWindFlags) {
    ASSERT_EQ(run(simulate("--steps 20 --wind turbulent --turbulence 0.5 --wind-seed 18446744073709551615 "
                           "--dump-nodes " + path("a.csv"))).exit_code,
              0)
        << last_.err;
    EXPECT_TRUE(fs::exists(path("a.csv")));
    expect_bad(simulate("--steps 2 --wind turbulent --wind-seed 18446744073709551616"), "--wind-seed");
    expect_bad(simulate("--steps 2 --wind turbulent --wind-seed -3"), "--wind-seed");
    expect_bad(simulate("--steps 2 --wind turbulent --wind-seed 1.5"), "--wind-seed");
    expect_bad(simulate("--steps 2 --wind turbulent --turbulence 2.5"), "--turbulence");
    expect_bad(simulate("--steps 2 --wind turbulent --turbulence -0.1"), "--turbulence");
}

// Needs the turbulent profile of docs/model.md 3.5 in the backends.
TEST_F(CliLive, TurbulentAndAtmosphericWindDependOnTheSeed) {
    for (std::string profile : {"turbulent", "atmospheric"}) {
        SCOPED_TRACE(profile);
        for (auto [seed, file] : {std::pair{"1", "s1.csv"}, std::pair{"1", "s1b.csv"}, std::pair{"2", "s2.csv"}})
            ASSERT_EQ(run(simulate("--steps 60 --wind " + profile + " --wind-seed " + seed + " --dump-nodes " +
                                   path(profile + file))).exit_code,
                      0)
                << last_.err;
        EXPECT_EQ(read_text(path(profile + "s1.csv")), read_text(path(profile + "s1b.csv")));
        EXPECT_NE(read_text(path(profile + "s1.csv")), read_text(path(profile + "s2.csv")));
    }
}

TEST_F(CliLive, MaxFrequencyDecidesTheCappedChains) {
    ASSERT_EQ(run("info --tree " + path("small.json") + " --json --max-frequency 0.05").exit_code, 0) << last_.err;
    const auto low = nlohmann::json::parse(last_.out);
    ASSERT_EQ(run("info --tree " + path("small.json") + " --json --max-frequency 1000").exit_code, 0) << last_.err;
    const auto high = nlohmann::json::parse(last_.out);
    EXPECT_GT(low["capped_chains"].get<int>(), high["capped_chains"].get<int>());
    EXPECT_EQ(low["capped_chains"].get<int>(), low["chains"].get<int>()) << "at 0.05 Hz every chain is capped";
    ASSERT_EQ(run("info --tree " + path("small.json") + " --max-frequency 0.05").exit_code, 0) << last_.err;
    EXPECT_NE(last_.out.find("capped chains    " + std::to_string(low["chains"].get<int>())),
              std::string::npos);
    // The cap changes the motion.
    ASSERT_EQ(run(simulate("--steps 40 --max-frequency 0.05 --dump-nodes " + path("a.csv"))).exit_code, 0) << last_.err;
    ASSERT_EQ(run(simulate("--steps 40 --dump-nodes " + path("b.csv"))).exit_code, 0) << last_.err;
    EXPECT_NE(read_text(path("a.csv")), read_text(path("b.csv")));
    expect_bad(simulate("--steps 2 --max-frequency 0"), "max_frequency");
    expect_bad(simulate("--steps 2 --max-frequency -4"), "max_frequency");
}

TEST_F(CliLive, IntegersBeyondTheirTypeAreRejectedAtOnce) {
    expect_bad(simulate("--steps 18446744073709551616"), "--steps");
    expect_bad(simulate("--steps 9223372036854775808"), "--steps");
    expect_bad(simulate("--steps 1e3"), "--steps");
    expect_bad(simulate("--steps 2 --instances 4294967296"), "--instances");
    expect_bad(simulate("--steps 2 --instances -1"), "--instances");
    expect_bad(simulate("--steps 2 --ring-sides 4294967299"), "--ring-sides");
    expect_bad(simulate("--steps 2 --instances 4 --seed 18446744073709551616"), "--seed");
}

TEST_F(CliLive, TooLargeAGridIsRefusedBeforeAnyAllocation) {
    // Sized from the model's counts first: a limit of this build (exit 1, as Simulation::create's
    // "scene too large"), reported at once instead of after gigabytes of instance list.
    for (const std::string& args : {std::string("simulate --preset paper-5 --backend cpu --steps 1 --instances 100000000"),
                                    simulate("--steps 1 --instances 4000000000")}) {
        SCOPED_TRACE(args);
        EXPECT_EQ(run(args + " --dump-nodes " + path("n.csv")).exit_code, 1) << last_.err;
        EXPECT_NE(last_.err.find("scene too large"), std::string::npos) << last_.err;
        EXPECT_EQ(std::count(last_.err.begin(), last_.err.end(), '\n'), 1) << last_.err;
        EXPECT_FALSE(fs::exists(path("n.csv")));
    }
    EXPECT_NE(last_.err.find("4000000000"), std::string::npos) << last_.err;
}

TEST_F(CliLive, ScheduleEventsAfterTheLastStepAreValidatedButNotApplied) {
    write("late.json", R"({"format": "hmsm-schedule", "version": 1, "events": [
        {"step": 50, "wind": {"strength": 9}, "forces": [{"center": [0, 1, 0], "radius": 3, "radial": 5}]}]})");
    ASSERT_EQ(
        run(simulate("--steps 20 --wind-schedule " + path("late.json") + " --dump-nodes " + path("a.csv"))).exit_code, 0)
        << last_.err;
    ASSERT_EQ(run(simulate("--steps 20 --dump-nodes " + path("b.csv"))).exit_code, 0) << last_.err;
    EXPECT_EQ(read_text(path("a.csv")), read_text(path("b.csv")));
    write("late_bad.json", R"({"format": "hmsm-schedule", "version": 1, "events": [
        {"step": 5000, "instances": [{"instance": 3, "active": false}]}]})");
    expect_bad(simulate("--steps 20 --wind-schedule " + path("late_bad.json")), "instance 3");
}

TEST_F(CliLive, BadSchedulesLeaveNoOutput) {
    write("s.json", R"({"format": "hmsm-schedule", "version": 1, "events": [
        {"step": 2, "wind": {"strength": 2}}, {"step": 1, "wind": {"strength": 1}}]})");
    const std::string outputs = " --dump-chains " + path("c.csv") + " --trace " + path("t.csv") + " --trace-nodes top --report " +
                                path("r.json");
    expect_bad(simulate("--steps 4 --wind-schedule " + path("s.json") + outputs), "non-decreasing");
    for (const char* f : {"c.csv", "t.csv", "r.json"}) EXPECT_FALSE(fs::exists(path(f))) << f;
    expect_bad(simulate("--steps 4 --wind-schedule " + path("missing.json")), "missing.json");
    write("s.json", R"({"format": "hmsm-schedule", "version": 1, "events": [
        {"step": 2, "add": [{"model": "oak"}]}]})");
    expect_bad(simulate("--steps 4 --wind-schedule " + path("s.json")), "oak");
}

// Needs the live-control calls of Simulation. A step-1 event that sets the wind the flags would
// set gives the flags' run; a later change gives a different one; a tree given with --tree is
// the model "tree".
TEST_F(CliLive, ScheduleDrivesTheRun) {
    write("s.json", R"({"format": "hmsm-schedule", "version": 1, "events": [
        {"step": 1, "wind": {"profile": "constant", "strength": 3}}]})");
    ASSERT_EQ(
        run(simulate("--steps 30 --wind-schedule " + path("s.json") + " --dump-chains " + path("a.csv"))).exit_code, 0)
        << last_.err;
    ASSERT_EQ(run(simulate("--steps 30 --wind constant --wind-strength 3 --dump-chains " + path("b.csv"))).exit_code, 0)
        << last_.err;
    EXPECT_EQ(read_text(path("a.csv")), read_text(path("b.csv")));
    write("s.json", R"({"format": "hmsm-schedule", "version": 1, "events": [
        {"step": 10, "forces": [{"center": [0, 1, 0], "radius": 6, "radial": 20}]},
        {"step": 20, "remove": [0], "add": [{"model": "tree", "origin": [3, 0, 0]}, {"model": "tree"}]}]})");
    ASSERT_EQ(run(simulate("--steps 30 --wind-schedule " + path("s.json") + " --dump-nodes " + path("c.csv") +
                           " --trace " + path("t.csv") + " --trace-nodes top")).exit_code,
              0)
        << last_.err;
    std::string header;
    Rows nodes = csv(path("c.csv"), header);
    EXPECT_EQ(nodes.size(), 2 * test::small_tree().nodes.size());  // the current list: two instances
    Rows trace = csv(path("t.csv"), header);
    EXPECT_EQ(trace.size(), 19u + 2u * 11u);  // one instance up to step 19, then two
}

TEST_F(CliLive, ProgressOnlyOnATerminal) {
    ASSERT_EQ(run(simulate("--steps 5")).exit_code, 0) << last_.err;
    EXPECT_EQ(last_.err.find("step 5/5"), std::string::npos) << "stderr is not a terminal here: " << last_.err;
    ASSERT_EQ(run(simulate("--steps 5 --no-progress")).exit_code, 0) << last_.err;
    EXPECT_EQ(std::count(last_.err.begin(), last_.err.end(), '\n'), 1) << last_.err;
}

// Needs wind_scale and active in the backends. A forest's wind_scale 0 and active false keep an
// instance in its rest pose (to the bit: no force, or no pass touches it); the others sway.
TEST_F(CliLive, ForestWindScaleAndActiveReachTheSimulation) {
    write("forest.json", R"({"format": "hmsm-forest", "version": 1, "models": {"t": "small.json"},
        "instances": [{"model": "t"}, {"model": "t", "origin": [6, 0, 0], "wind_scale": 0},
                      {"model": "t", "origin": [12, 0, 0], "active": false},
                      {"model": "t", "origin": [18, 0, 0], "wind_scale": 2, "wind_phase": 0.5}]})");
    const std::string forest = "simulate --forest " + path("forest.json") + " --backend cpu64 --wind constant ";
    ASSERT_EQ(run(forest + "--steps 0 --dump-nodes " + path("rest.csv")).exit_code, 0) << last_.err;
    ASSERT_EQ(run(forest + "--steps 40 --dump-nodes " + path("moved.csv")).exit_code, 0) << last_.err;
    std::string header;
    Rows rest = csv(path("rest.csv"), header), moved = csv(path("moved.csv"), header);
    const size_t n = test::small_tree().nodes.size();
    ASSERT_EQ(rest.size(), 4 * n);
    ASSERT_EQ(moved.size(), 4 * n);
    auto same = [&](size_t instance) {
        for (size_t k = instance * n; k < (instance + 1) * n; ++k)
            if (rest[k] != moved[k]) return false;
        return true;
    };
    EXPECT_FALSE(same(0));
    EXPECT_TRUE(same(1)) << "wind_scale 0: no wind";
    EXPECT_TRUE(same(2)) << "inactive: frozen";
    EXPECT_FALSE(same(3));
}

// A schedule may add instances of a forest model that no forest instance places: the CLI asks
// the forest loader for the schedule's models.
TEST_F(CliLive, ScheduleAddsAModelTheForestDoesNotPlace) {
    ASSERT_TRUE(save_tree(test::rod(), path("rod.json")).ok());
    write("forest.json", R"({"format": "hmsm-forest", "version": 1,
        "models": {"t": "small.json", "r": "rod.json", "unused": "broken.json"}, "instances": [{"model": "t"}]})");
    write("broken.json", "not a tree");
    write("s.json", R"({"format": "hmsm-schedule", "version": 1, "events": [
        {"step": 3, "add": [{"model": "r", "origin": [4, 0, 0]}]}]})");
    ASSERT_EQ(run("simulate --forest " + path("forest.json") + " --backend cpu64 --steps 6 --wind-schedule " +
                  path("s.json") + " --dump-nodes " + path("n.csv"))
                  .exit_code,
              0)
        << last_.err;
    std::string header;
    EXPECT_EQ(csv(path("n.csv"), header).size(), test::small_tree().nodes.size() + test::rod().nodes.size());
    write("bad.json", R"({"format": "hmsm-schedule", "version": 1, "events": [
        {"step": 3, "add": [{"model": "unused"}]}]})");
    expect_bad("simulate --forest " + path("forest.json") + " --backend cpu64 --steps 6 --wind-schedule " +
                   path("bad.json"),
               "models.unused");
}
