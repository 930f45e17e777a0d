// The input limits and the output rules through the CLI (docs/model.md 3.11, docs/cli.md
// "Outputs"): out-of-range values exit 2 with one short line, outputs never clash with each
// other or with an input, and a replaced file keeps its mode; links and special files are
// never replaced.
#include "cli_fixture.h"
#include "test_trees.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace hmsm {
namespace {

namespace fs = std::filesystem;

class CliLimits : public test::CliFixture {
protected:
    void write(const std::string& name, const std::string& text) const { std::ofstream(path(name)) << text; }
    std::string read(const std::string& name) const { return test::read_text(path(name)); }

    /// Exit `code`, one line of stderr containing `fragment`, no staged temporary left behind.
    void expect_refused(const std::string& args, int code, const std::string& fragment) {
        SCOPED_TRACE(args);
        const test::CliRun r = run(args);
        EXPECT_EQ(r.exit_code, code) << r.err;
        EXPECT_NE(r.err.find(fragment), std::string::npos) << r.err;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err.substr(0, 400);
        EXPECT_LT(r.err.size(), 600u);
        for (const std::string& name : entries()) EXPECT_EQ(name.find(".tmp-hmsm"), std::string::npos) << name;
    }
    std::string simulate() const { return "simulate --tree " + path("small.json") + " --backend cpu --steps 2 "; }
};

TEST_F(CliLimits, ValuesBeyondFloatRangeExitTwo) {
    write("radial.json", R"({"format": "hmsm-schedule", "version": 1, "events": [
        {"step": 1, "forces": [{"center": [0, 1, 0], "radius": 5, "radial": 1e39}]}]})");
    expect_refused(simulate() + "--wind-schedule " + path("radial.json") + " --dump-nodes " + path("n.csv"), 2,
                   "radial");
    EXPECT_FALSE(fs::exists(path("n.csv")));
    write("center.json", R"({"format": "hmsm-schedule", "version": 1, "events": [
        {"step": 1, "forces": [{"center": [1e308, 0, 0], "radius": 1e308, "directional": [1, 0, 0]}]}]})");
    expect_refused(simulate() + "--wind-schedule " + path("center.json"), 2, "center");
    write("scale.json", R"({"format": "hmsm-schedule", "version": 1, "events": [
        {"step": 1, "instances": [{"instance": 0, "wind_scale": 1e28}]}]})");
    expect_refused(simulate() + "--wind-schedule " + path("scale.json"), 2, "wind_scale");
    write("forest.json", R"({"format": "hmsm-forest", "version": 1, "models": {"t": "small.json"},
        "instances": [{"model": "t", "wind_scale": 1e28}]})");
    expect_refused("simulate --forest " + path("forest.json") + " --backend cpu --steps 2", 2, "wind_scale");
    write("origin.json", R"({"format": "hmsm-forest", "version": 1, "models": {"t": "small.json"},
        "instances": [{"model": "t", "origin": [0, 0, 1e300]}]})");
    expect_refused("simulate --forest " + path("origin.json") + " --backend cpu --steps 2", 2, "origin");
    write("scale5.json", R"({"format": "hmsm-schedule", "version": 1, "events": [
        {"step": 1, "instances": [{"instance": 0, "wind_scale": 1e5}]}]})");
    expect_refused(simulate() + "--wind-strength 1e26 --wind-schedule " + path("scale5.json") + " --report " +
                       path("r.json"),
                   2, "wind force");
    EXPECT_FALSE(fs::exists(path("r.json")));
    expect_refused(simulate() + "--wind-frequency 1e308", 2, "wind frequency");
    expect_refused(simulate() + "--wind-strength 3.5e38", 2, "wind strength");
}

TEST_F(CliLimits, SizesAreRefusedBeforeBuilding) {
    const auto start = std::chrono::steady_clock::now();
    expect_refused("simulate --preset paper-5 --backend cpu --steps 1 --instances 16777216", 1,
                   std::to_string(kMaxInstances));
    const int fd = ::open(path("sparse.txt").c_str(), O_CREAT | O_TRUNC | O_WRONLY, 0644);
    ASSERT_GE(fd, 0);
    ASSERT_EQ(::ftruncate(fd, off_t(2) << 30), 0);
    ::close(fd);
    expect_refused("import --treeqsm " + path("sparse.txt") + " --out " + path("t.json"), 2, "256 MiB");
    expect_refused("import --treeqsm /dev/urandom --out " + path("t.json"), 2, "not a regular file");
    EXPECT_FALSE(fs::exists(path("t.json")));
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 20.0);
    write("format.json", R"({"format": ")" + std::string(1 << 20, 'x') + R"(", "version": 1, "nodes": []})");
    expect_refused("simulate --tree " + path("format.json") + " --backend cpu", 2, "format");
}

TEST_F(CliLimits, TwoOutputsOnOnePathAreRefusedBeforeRunning) {
    write("x.csv", "keep me\n");
    expect_refused(simulate() + "--dump-nodes " + path("x.csv") + " --report " + path("x.csv"), 2, "same file");
    EXPECT_EQ(read("x.csv"), "keep me\n");
    expect_refused(simulate() + "--dump-nodes " + path("x.csv") + " --report " + path("sub/../x.csv"), 2,
                   "same file");
    // An output onto an input.
    const std::string tree = read("small.json");
    expect_refused(simulate() + "--dump-nodes " + path("small.json"), 2, "input");
    EXPECT_EQ(read("small.json"), tree);
    expect_refused("import --treeqsm " + path("small.json") + " --out " + path("small.json"), 2, "input");
    EXPECT_EQ(read("small.json"), tree);
}

TEST_F(CliLimits, ReplacedOutputsKeepTheirModeLinksAndSpecialFilesAreRefused) {
    write("private.csv", "old\n");
    ASSERT_EQ(::chmod(path("private.csv").c_str(), 0600), 0);
    const test::CliRun replaced = run(simulate() + "--dump-nodes " + path("private.csv"));
    ASSERT_EQ(replaced.exit_code, 0) << replaced.err;
    EXPECT_EQ(fs::status(path("private.csv")).permissions() & fs::perms::mask,
              fs::perms::owner_read | fs::perms::owner_write);
    EXPECT_NE(read("private.csv"), "old\n");

    write("target.csv", "target\n");
    fs::create_symlink(path("target.csv"), path("link.csv"));
    expect_refused(simulate() + "--dump-nodes " + path("link.csv"), 2, "symbolic link");
    EXPECT_TRUE(fs::is_symlink(path("link.csv")));
    EXPECT_EQ(read("target.csv"), "target\n");

    ASSERT_EQ(::mkfifo(path("fifo").c_str(), 0644), 0);
    expect_refused(simulate() + "--report " + path("fifo"), 2, "not a regular file");
    EXPECT_TRUE(fs::is_fifo(path("fifo")));
    expect_refused("generate --preset paper-5 --out " + path("fifo"), 2, "not a regular file");
    EXPECT_TRUE(fs::is_fifo(path("fifo")));
}

}  // namespace
}  // namespace hmsm
