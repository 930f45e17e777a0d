// hmsm simulate --outputs and --dump-chains (docs/model.md 5, 3.10): the chain dump is every
// instance's O_c and R_c column by column as %.17g, equal to the library's joint matrices, with
// any --outputs; dumps of outputs not produced are bad input (exit 2, no file).
#include "cli_fixture.h"
#include "test_trees.h"

#include <nlohmann/json.hpp>
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

using namespace hmsm;

namespace {

class JointsCli : public test::CliFixture {};

std::vector<std::vector<double>> read_csv(const std::string& file, std::string& header) {
    std::ifstream in(file);
    std::getline(in, header);
    std::vector<std::vector<double>> rows;
    for (std::string line; std::getline(in, line);) {
        std::vector<double> row;
        std::stringstream cells(line);
        for (std::string cell; std::getline(cells, cell, ',');) row.push_back(std::strtod(cell.c_str(), nullptr));
        rows.push_back(row);
    }
    return rows;
}

TEST_F(JointsCli, DumpChainsEqualsTheLibrarysJointMatricesForEveryOutputs) {
    // The same run in the library (cpu64: the dump must round-trip its doubles exactly).
    SimulationConfig config;
    config.backend = BackendKind::cpu64;
    config.wind.strength = 4.0;
    auto sim = Simulation::create(single_tree_scene(test::small_tree(), {1, 0, 2}, 0.7), config);
    ASSERT_TRUE(sim.ok()) << sim.status().message();
    ASSERT_TRUE((*sim)->step(50).ok());
    std::vector<double> joints;
    ASSERT_TRUE((*sim)->read(Output::joint_matrices, joints).ok());
    const uint64_t chains = (*sim)->chain_count();
    for (const std::string outputs : {"joints", "nodes", "all"}) {
        SCOPED_TRACE(outputs);
        const test::CliRun r = run("simulate --tree " + path("small.json") +
                                   " --backend cpu64 --steps 50 --wind-strength 4 --origin 1,0,2 --yaw 0.7 --outputs " +
                                   outputs + " --dump-chains " + path("chains.csv"));
        ASSERT_EQ(r.exit_code, 0) << r.err;
        std::string header;
        auto rows = read_csv(path("chains.csv"), header);
        EXPECT_EQ(header, "instance,chain,ox,oy,oz,r00,r10,r20,r01,r11,r21,r02,r12,r22");
        ASSERT_EQ(rows.size(), chains);
        for (uint64_t c = 0; c < chains; ++c) {
            ASSERT_EQ(rows[c].size(), 14u);
            EXPECT_EQ(rows[c][0], 0.0);
            EXPECT_EQ(rows[c][1], double(c));
            const double* m = &joints[12 * c];  // rows (R row i, O_i)
            for (int i = 0; i < 3; ++i) EXPECT_EQ(rows[c][2 + i], m[4 * i + 3]);
            for (int col = 0; col < 3; ++col)
                for (int row = 0; row < 3; ++row) EXPECT_EQ(rows[c][5 + 3 * col + row], m[4 * row + col]);
        }
    }
}

TEST_F(JointsCli, DumpsOfOutputsNotProducedAreBadInput) {
    for (const auto& [outputs, dump] : {std::pair{"joints", "--dump-nodes"}, std::pair{"joints", "--dump-vertices"},
                                        std::pair{"nodes", "--dump-vertices"}, std::pair{"everything", "--dump-chains"}}) {
        expect_bad_input("simulate --tree " + path("small.json") + " --backend cpu --steps 2 --outputs " + outputs +
                             " " + dump + " " + path("out.file"),
                         "--");
    }
}

/// hmsm bench's joints-only forest rows: one per size, passes 1-5 only, 48 bytes per joint.
TEST_F(JointsCli, BenchWritesJointsOnlyForestRows) {
    const test::CliRun r = run("bench --quick --no-progress --backends cpu --presets none --instances none "
                               "--joint-instances 1,3 --json " + path("bench.json") + " --commit test");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    std::ifstream in(path("bench.json"));
    const nlohmann::json d = nlohmann::json::parse(in, nullptr, false);
    ASSERT_TRUE(d.is_object());
    ASSERT_TRUE(d["forest_joints"].is_array());
    ASSERT_EQ(d["forest_joints"].size(), 2u) << d["skipped"].dump();
    auto paper = generate_preset("paper-1");
    ASSERT_TRUE(paper.ok());
    SimulationConfig config;
    config.backend = BackendKind::cpu;
    auto one = Simulation::create(single_tree_scene(*paper), config);
    ASSERT_TRUE(one.ok());
    for (const auto& row : d["forest_joints"]) {
        const uint64_t n = row.value("instances", 0ull);
        EXPECT_EQ(row.value("outputs", ""), "joints");
        EXPECT_EQ(row.value("chains", 0ull), n * (*one)->chain_count());
        EXPECT_EQ(row.value("joint_bytes", 0ull), 48 * n * (*one)->chain_count());
        EXPECT_GT(row.value("seconds_per_step", 0.0), 0.0);
        EXPECT_GT(row.value("bytes_per_step", 0.0), 0.0);
        // The same forest with path walks.
        ASSERT_TRUE(row.contains("path_walk")) << row.dump();
        EXPECT_GT(row["path_walk"].value("seconds_per_step", 0.0), 0.0);
        EXPECT_FALSE(row.contains("fused")) << row.dump();
    }
    EXPECT_NE(r.out.find("### Forest scaling, joints only"), std::string::npos) << r.out;
}

}  // namespace
