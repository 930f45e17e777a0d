// The command-line contract (docs/model.md 5): exit codes, one clear error line, no partial output.
#include "cli_fixture.h"
#include "test_trees.h"

#include <nlohmann/json.hpp>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>

using namespace hmsm;
namespace fs = std::filesystem;

namespace {

using test::CliRun;

class Cli : public test::CliFixture {
protected:
    /// Bad input to a command that would otherwise write nodes.csv.
    void expect_bad_input(const std::string& args, const std::string& fragment) {
        CliFixture::expect_bad_input(args + " --dump-nodes " + path("nodes.csv"), fragment);
    }
};

}  // namespace

TEST_F(Cli, SimulateWritesNodesVerticesAndReport) {
    CliRun r = run("simulate --tree " + path("small.json") + " --backend cpu --steps 30 --dump-nodes " +
                path("n.csv") + " --dump-vertices " + path("v.bin") + " --report " + path("r.json") +
                " --origin 1,0,2 --yaw 0.5");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    std::ifstream csv(path("n.csv"));
    std::string line;
    std::getline(csv, line);
    EXPECT_EQ(line, "instance,node,x,y,z");
    int rows = 0;
    while (std::getline(csv, line)) ++rows;
    EXPECT_EQ(rows, int(test::small_tree().nodes.size()));

    auto h = build_hierarchy(test::small_tree(), {});
    uint64_t vertices = mesh_vertex_count(test::small_tree(), *h, {});
    EXPECT_EQ(fs::file_size(path("v.bin")), vertices * 3 * sizeof(float));

    std::ifstream report_file(path("r.json"));
    auto report = nlohmann::json::parse(report_file);
    EXPECT_EQ(report["backend"], "cpu");
    EXPECT_EQ(report["steps"], 30);
    EXPECT_EQ(report["mesh_vertices"], vertices);
    for (Pass p : kAllPasses) EXPECT_GT(report["pass_device_seconds"][std::string(pass_name(p))].get<double>(), 0.0);
}

TEST_F(Cli, PackedVertexLayoutDumpsTheSameVertices) {
    for (const std::string layout : {"separate", "packed"}) {
        CliRun r = run("simulate --tree " + path("small.json") + " --backend cpu --steps 20 --vertex-layout " +
                       layout + " --dump-vertices " + path(layout + ".bin") + " --report " + path(layout + ".json"));
        ASSERT_EQ(r.exit_code, 0) << r.err;
        std::ifstream report_file(path(layout + ".json"));
        EXPECT_EQ(nlohmann::json::parse(report_file)["vertex_layout"], layout);
    }
    auto bytes = [&](const std::string& name) {
        std::ifstream in(path(name), std::ios::binary);
        return std::string(std::istreambuf_iterator<char>(in), {});
    };
    EXPECT_FALSE(bytes("separate.bin").empty());
    EXPECT_EQ(bytes("separate.bin"), bytes("packed.bin"));
}

TEST_F(Cli, GridForestDumpsEveryInstance) {
    CliRun r = run("simulate --tree " + path("small.json") +
                " --instances 3 --spacing 4 --seed 9 --backend cpu64 --steps 5 --dump-nodes " + path("n.csv"));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    std::ifstream csv(path("n.csv"));
    std::string line, last;
    while (std::getline(csv, line)) last = line;
    EXPECT_EQ(last.rfind("2,15,", 0), 0u) << last;
}

TEST_F(Cli, InfoPrintsCountsAndChains) {
    CliRun r = run("info --tree " + path("small.json") + " --json --chains " + path("chains.csv"));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    auto info = nlohmann::json::parse(last_.out);
    auto h = build_hierarchy(test::small_tree(), {});
    EXPECT_EQ(info["nodes"], 16);
    EXPECT_EQ(info["chains"], h->chains.size());
    EXPECT_EQ(info["max_depth"], 3);
    EXPECT_EQ(info["leaves"], 3);
    EXPECT_EQ(info["mesh_vertices"], mesh_vertex_count(test::small_tree(), *h, {}));
    std::ifstream csv(path("chains.csv"));
    std::string header, trunk;
    std::getline(csv, header);
    std::getline(csv, trunk);
    EXPECT_EQ(header, "chain,parent,depth,attach_node,nodes");
    EXPECT_EQ(trunk, "0,-1,0,1,2 3 0");  // the trunk lists its members, not the root
}

TEST_F(Cli, BadArgumentsExitTwoWithoutOutput) {
    const std::string tree = " --tree " + path("small.json");
    expect_bad_input("simulate" + tree + " --dt 0", "dt");
    expect_bad_input("simulate" + tree + " --dt -0.1", "dt");
    expect_bad_input("simulate" + tree + " --steps -1", "steps");
    expect_bad_input("simulate" + tree + " --backend quantum", "backend");
    expect_bad_input("simulate" + tree + " --wind gale", "wind");
    expect_bad_input("simulate" + tree + " --wind-dir 0,0,0", "direction");
    expect_bad_input("simulate" + tree + " --wind-dir 1,0", "wind-dir");
    expect_bad_input("simulate" + tree + " --wind-frequency -1", "frequency");
    expect_bad_input("simulate" + tree + " --front-speed -2", "front speed");
    expect_bad_input("simulate" + tree + " --stiffness 0", "stiffness");
    expect_bad_input("simulate" + tree + " --damping-ratio -1", "damping");
    expect_bad_input("simulate" + tree + " --max-angle 3", "max_angle");
    expect_bad_input("simulate" + tree + " --ring-sides 2", "ring_sides");
    expect_bad_input("simulate" + tree + " --fix-weight 2", "fix_weight");
    expect_bad_input("simulate" + tree + " --grouping height", "grouping");
    expect_bad_input("simulate" + tree + " --vertex-layout interleaved", "--vertex-layout");
    expect_bad_input("simulate" + tree + " --composition fused", "--composition 'fused'");
    expect_bad_input("simulate" + tree + " --origin 1,2,x", "origin");
    expect_bad_input("simulate" + tree + " --no-such-flag", "no-such-flag");
    expect_bad_input("simulate --steps 3", "--tree");
    expect_bad_input("simulate --tree " + path("missing.json"), "missing.json");
    expect_bad_input("simulate" + tree + " --steps abc", "steps");
}

TEST_F(Cli, ChoiceErrorsListTheNameTables) {
    const std::string tree = " --tree " + path("small.json");
    expect_bad_input("simulate" + tree + " --composition rounds",
                     "expected pointer-jumping, level-by-level, path-walk or automatic");
    // Pointer jumping chooses its dispatch form by size: the forms are not compositions.
    for (const char* form : {"pointer-jumping-per-round", "pointer_jumping_in_dispatch"})
        expect_bad_input("simulate" + tree + " --composition " + form, std::string("--composition '") + form + "'");
    expect_bad_input("simulate" + tree + " --outputs vertices", "expected joints, nodes or all");
    expect_bad_input("simulate" + tree + " --wind gale", "expected none, constant, y1, y2, y3, y4, turbulent or atmospheric");
    CliFixture::expect_bad_input("bench --no-progress --forest-composition rounds",
                                 "--forest-composition 'rounds': expected pointer-jumping");
    // Compositions are accepted with '-' or '_' between words.
    for (const char* name : {"path-walk", "path_walk"}) {
        CliRun r = run("simulate" + tree + " --backend cpu --steps 1 --composition " + name);
        EXPECT_EQ(r.exit_code, 0) << name << ": " << r.err;
    }
}

TEST_F(Cli, BackendErrorsAreTheSameInEverySubcommand) {
    const std::string backends = "expected cpu, cpu64, cpu-parallel, vulkan, cuda or auto";
    expect_bad_input("simulate --tree " + path("small.json") + " --backend quantum",
                     "--backend 'quantum': " + backends);
    CliFixture::expect_bad_input("export --preset paper-1 --seconds 1 --fps 10 --gltf " + path("e.glb") +
                                     " --backend quantum",
                                 "--backend 'quantum': " + backends);
    // bench runs named backends only: no "auto".
    CliFixture::expect_bad_input("bench --no-progress --backends cpu,auto",
                                 "--backends 'auto': expected cpu, cpu64, cpu-parallel, vulkan or cuda");
}

TEST_F(Cli, BadTreeFilesExitTwoNamingTheNode) {
    std::ofstream(path("cycle.json")) << R"({"format": "hmsm-tree", "version": 1, "nodes": [
        {"parent": -1, "position": [0,0,0], "radius": 0.3},
        {"parent": 2, "position": [0,1,0], "radius": 0.2},
        {"parent": 1, "position": [0,2,0], "radius": 0.2}]})";
    expect_bad_input("simulate --tree " + path("cycle.json"), "cycle");
    std::ofstream(path("radius.json")) << R"({"format": "hmsm-tree", "version": 1, "nodes": [
        {"parent": -1, "position": [0,0,0], "radius": 0.3},
        {"parent": 0, "position": [0,1,0], "radius": 0}]})";
    expect_bad_input("simulate --tree " + path("radius.json"), "node 1");
    std::ofstream(path("text.json")) << "hello";
    expect_bad_input("simulate --tree " + path("text.json"), "JSON");
}

TEST_F(Cli, UnwritableOutputFailsBeforeSimulating) {
    CliRun r = run("simulate --tree " + path("small.json") + " --steps 1 --dump-nodes " +
                path("no/such/dir/n.csv"));
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("no/such/dir/n.csv"), std::string::npos) << r.err;
}

TEST_F(Cli, UnavailableBackendExitsOne) {
    for (const char* backend : {"cuda", "vulkan"}) {
        bool compiled = false;
        for (BackendKind k : compiled_backends()) compiled |= std::string(to_string(k)) == backend;
        CliRun r = run("simulate --tree " + path("small.json") + " --steps 1 --backend " + backend);
        if (r.exit_code == 0) continue;  // a device exists on this machine
        EXPECT_EQ(r.exit_code, 1) << r.err;
        EXPECT_NE(r.err.find(backend), std::string::npos) << r.err;
        if (!compiled) EXPECT_NE(r.err.find("no"), std::string::npos);
    }
}

// The acceptance commands of the core issue.
TEST_F(Cli, PresetInfoAndSimulateAcceptance) {
    CliRun r = run("info --preset paper-1 --json");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    auto info = nlohmann::json::parse(last_.out);
    EXPECT_NEAR(info["mesh_vertices"].get<double>(), 78563.0, 785.63);
    EXPECT_EQ(info["max_depth"], 4);
    EXPECT_GT(info["leaves"].get<int>(), 0);

    r = run("simulate --preset paper-5 --backend cpu --steps 60 --dump-nodes " + path("out.csv") +
            " --report " + path("r.json"));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    std::ifstream report_file(path("r.json"));
    auto report = nlohmann::json::parse(report_file);
    for (Pass p : kAllPasses)
        EXPECT_GT(report["pass_device_seconds"][std::string(pass_name(p))].get<double>(), 0.0);
    EXPECT_TRUE(fs::exists(path("out.csv")));

    r = run("generate --preset paper-2 --seed 3 --out " + path("p2.json"));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    auto tree = load_tree(path("p2.json"));
    ASSERT_TRUE(tree.ok()) << tree.status().message();
    r = run("generate --preset paper-9 --out " + path("p9.json"));
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("paper-9"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(path("p9.json")));
}

/// Every command that can run long takes --no-progress (render and bench: in their own tests);
/// the progress itself is drawn only on a terminal, never into a redirected stderr.
TEST_F(Cli, LongRunningCommandsAcceptNoProgress) {
    CliRun r = run("simulate --tree " + path("small.json") + " --backend cpu --steps 5 --no-progress");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    r = run("export --gltf " + path("clip.glb") + " --tree " + path("small.json") +
            " --seconds 0.2 --fps 10 --no-progress");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    EXPECT_TRUE(fs::exists(path("clip.glb")));
    EXPECT_EQ(r.err.find('\r'), std::string::npos) << r.err;
    r = run("analyze --tree " + path("small.json") + " --step-seconds 1 --spectrum-seconds 1 --no-progress --json");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("\"models\""), std::string::npos);
    EXPECT_EQ(r.err.find('\r'), std::string::npos) << r.err;
}

/// The levels of detail in hmsm info (docs/model.md 3.12): one per budget, finest first, with
/// their joint counts, an f0 ratio of 1 and a geometric error that grows as joints go; a budget
/// below the trunk-only level is bad input.
TEST_F(Cli, InfoListsTheLevelsOfDetail) {
    CliRun r = run("info --preset paper-5 --json --levels 16,256,1,64");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    auto info = nlohmann::json::parse(last_.out);
    ASSERT_EQ(info["levels"].size(), 4u);
    const int expected[] = {256, 64, 16, 1};
    for (size_t i = 0; i < 4; ++i) {
        const auto& level = info["levels"][i];
        EXPECT_EQ(level["budget"], expected[i]);
        EXPECT_EQ(level["joints"], expected[i]);
        EXPECT_NEAR(level["frequency_ratio"].get<double>(), 1.0, 0.05);
        EXPECT_NEAR(level["trunk_frequency_hz"].get<double>(), info["trunk_frequency_hz"].get<double>(), 1e-12);
        if (i > 0)
            EXPECT_GE(level["geometric_error_m"].get<double>(), info["levels"][i - 1]["geometric_error_m"].get<double>());
    }
    EXPECT_GT(info["levels"][3]["geometric_error_m"].get<double>(), 0.0);
    CliRun text = run("info --tree " + path("small.json"));
    ASSERT_EQ(text.exit_code, 0) << text.err;
    EXPECT_NE(text.out.find("f0 ratio"), std::string::npos) << text.out;
    // With --chains: a refused budget leaves no chain table behind.
    CliFixture::expect_bad_input("info --tree " + path("small.json") + " --levels 16,0 --chains " + path("c.csv"),
                                 "trunk-only");
    CliFixture::expect_bad_input("info --tree " + path("small.json") + " --levels 16,x --chains " + path("c.csv"),
                                 "--levels");
}
