// `hmsm bench --quick` through the CLI binary: the JSON schema of docs/benchmarks/README.md, every
// figure finite and positive, the markdown on stdout and --render agreeing. No timing thresholds.
#include <hmsm/simulation.h>

#include <nlohmann/json.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <sys/wait.h>

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

struct BenchRun {
    int exit_code;
    std::string out, err;
};

std::string slurp(const fs::path& path) {
    std::ifstream in(path);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

class BenchCli : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() /
               ("hmsm_bench_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }

    BenchRun run(const std::string& args) const {
        const std::string command = std::string(HMSM_CLI_PATH) + " " + args + " > " +
                                    (dir_ / "stdout.txt").string() + " 2> " + (dir_ / "stderr.txt").string();
        const int status = std::system(command.c_str());
        return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(dir_ / "stdout.txt"),
                slurp(dir_ / "stderr.txt")};
    }

    /// Runs the quick bench on one backend; returns its JSON document.
    json quick(const std::string& backend, BenchRun& r) {
        const std::string path = (dir_ / "bench.json").string();
        r = run("bench --quick --no-progress --backends " + backend + " --json " + path + " --commit test");
        EXPECT_EQ(r.exit_code, 0) << r.err;
        if (!fs::exists(path)) return json();
        json document = json::parse(slurp(path), nullptr, false);
        EXPECT_FALSE(document.is_discarded()) << "not JSON";
        return document;
    }

    fs::path dir_;
};

/// Every number under `j` is finite and positive; nothing is null (NaN and inf dump as null).
void expect_figures_positive(const json& j, const std::string& where) {
    if (j.is_null()) {
        ADD_FAILURE() << where << " is null";
    } else if (j.is_number()) {
        const double v = j.get<double>();
        EXPECT_TRUE(std::isfinite(v) && v > 0.0) << where << " = " << v;
    } else if (j.is_object()) {
        for (const auto& [key, value] : j.items()) expect_figures_positive(value, where + "." + key);
    } else if (j.is_array()) {
        for (size_t i = 0; i < j.size(); ++i) expect_figures_positive(j[i], where + "[" + std::to_string(i) + "]");
    }
}

void expect_number(const json& j, const char* key, const std::string& where) {
    ASSERT_TRUE(j.is_object()) << where;
    ASSERT_TRUE(j.contains(key) && j[key].is_number()) << where << " lacks number '" << key << "'";
}

/// The path walk's times: one per dispatch, a walk pair under "LEADER+PARTNER".
void expect_path_walk_pass_table(const json& j, const std::string& where) {
    ASSERT_TRUE(j.is_object()) << where;
    for (const char* key : {"wind_force+integrate", "compose+root_positions", "node_relative+node_world", "contour"})
        expect_number(j, key, where);
    EXPECT_EQ(j.size(), 4u) << where;
}

void expect_pass_table(const json& j, const std::string& where) {
    ASSERT_TRUE(j.is_object()) << where;
    for (const char* pass : {"wind_force", "integrate", "compose", "node_relative", "root_positions",
                             "node_world", "contour"})
        expect_number(j, pass, where);
    EXPECT_EQ(j.size(), 7u) << where;
}

/// The schema of docs/benchmarks/README.md for a quick run of `backend` (cpu always measured).
void expect_schema(const json& d, const std::string& backend) {
    ASSERT_TRUE(d.is_object());
    EXPECT_EQ(d.value("format", ""), "hmsm-bench");
    EXPECT_EQ(d.value("version", 0), 1);
    EXPECT_TRUE(d["date"].is_string());
    EXPECT_EQ(d.value("commit", ""), "test");
    EXPECT_EQ(d.value("quick", false), true);
    EXPECT_TRUE(d["host"]["cpu"].is_string());
    expect_number(d["host"], "hardware_threads", "host");
    for (const char* key : {"steps_per_batch", "warmup_steps", "repeats", "case_budget_seconds", "spacing"})
        expect_number(d["settings"], key, "settings");
    EXPECT_EQ(d["settings"]["instances"], json::array({1, 10}));
    EXPECT_EQ(d["settings"].value("forest_model", ""), "paper-1");
    for (const char* key : {"backends", "presets", "forest", "copy_bandwidth", "skipped", "notes"})
        ASSERT_TRUE(d.contains(key) && d[key].is_array()) << key;

    ASSERT_EQ(d["presets"].size(), 1u);
    const json& p = d["presets"][0];
    EXPECT_EQ(p.value("preset", ""), "paper-5");
    EXPECT_EQ(p.value("backend", ""), backend);
    EXPECT_TRUE(p["device"].is_string());
    for (const char* key : {"nodes", "chains", "mesh_vertices", "instances", "steps_per_batch", "repeats",
                            "effective_bandwidth"})
        expect_number(p, key, "presets[0]");
    EXPECT_TRUE(p["budget_reduced"].is_boolean());
    for (const char* key : {"per_call", "batched", "readback"}) {
        expect_number(p["steps_per_second"], key, "steps_per_second");
        expect_number(p["speedup_over_cpu"], key, "speedup_over_cpu");
        expect_number(p["speedup_over_best_cpu"], key, "speedup_over_best_cpu");
        ASSERT_TRUE(p["best_cpu"].is_object() && p["best_cpu"][key].is_string()) << p.dump();
        const std::string best = p["best_cpu"][key];
        EXPECT_TRUE(best == "cpu" || best == "cpu-parallel" || best == "cpu64") << best;
        // The best CPU backend is at least as fast as cpu.
        EXPECT_LE(p["speedup_over_best_cpu"][key].get<double>(), p["speedup_over_cpu"][key].get<double>() * (1 + 1e-12));
    }
    for (const char* key : {"state", "static", "total"}) expect_number(p["bytes_per_step"], key, "bytes_per_step");
    expect_pass_table(p["bytes_per_step"]["per_pass"], "bytes_per_step.per_pass");
    EXPECT_FALSE(p.contains("fused"));  // the compositions are those of the menu only
    for (const char* mode : {"pointer_jumping", "pointer_jumping_in_dispatch", "level_by_level", "path_walk"}) {
        const json& m = p[mode];
        const bool by_level = mode == std::string("level_by_level") || mode == std::string("path_walk");
        expect_number(m, by_level ? "levels" : "rounds", mode);
        for (const char* key : {"steps_per_second_batched", "steps_per_second_profiled",
                                "device_seconds_per_step", "device_effective_bandwidth"})
            expect_number(m, key, mode);
        if (mode == std::string("path_walk"))
            expect_path_walk_pass_table(m["pass_seconds_per_step"], "path_walk.pass_seconds_per_step");
        else expect_pass_table(m["pass_seconds_per_step"], std::string(mode) + ".pass_seconds_per_step");
    }

    // Forest: 1 and 10 instances of paper-1, each measured or skipped with a reason.
    EXPECT_EQ(d["settings"]["forest_layouts"], json::array({"separate", "packed"}));
    for (const json& f : d["forest"]) {
        const std::string layout = f.value("layout", "");
        EXPECT_TRUE(layout == "separate" || layout == "packed") << f.dump();
    }
    for (uint32_t n : {1u, 10u}) {
        std::map<std::string, const json*> measured;  // by layout
        for (const std::string layout : {"separate", "packed"}) {
            for (const json& f : d["forest"])
                if (f.value("instances", 0u) == n && f.value("backend", "") == backend &&
                    f.value("layout", "") == layout)
                    measured[layout] = &f;
            bool skipped = false;
            for (const json& s : d["skipped"])
                if (s.value("section", "") == "forest" && s.value("instances", 0u) == n &&
                    s.value("backend", "") == backend && s.value("layout", "") == layout) {
                    skipped = true;
                    EXPECT_TRUE(s["reason"].is_string());
                }
            ASSERT_TRUE(measured.count(layout) || skipped) << "forest " << n << " " << layout;
            if (!measured.count(layout)) continue;
            for (const char* key : {"mesh_vertices", "seconds_per_step", "steps_per_second", "vertices_per_second",
                                    "bytes_per_step", "state_bytes_per_step", "effective_bandwidth",
                                    "device_seconds_per_step", "device_effective_bandwidth",
                                    "copy_bandwidth_fraction", "device_copy_bandwidth_fraction",
                                    "steps_per_batch", "repeats"})
                expect_number(*measured[layout], key, "forest " + std::to_string(n) + " " + layout);
            // Speed-ups where cpu measured the same size and layout (it may be skipped by budget).
            const json& f = *measured[layout];
            if (f.contains("speedup_over_cpu")) {
                expect_number(f, "speedup_over_best_cpu", "forest speed-up");
                EXPECT_TRUE(f["best_cpu"].is_string());
                EXPECT_LE(f["speedup_over_best_cpu"].get<double>(), f["speedup_over_cpu"].get<double>() * (1 + 1e-12));
            }
        }
        if (measured.count("separate") && measured.count("packed")) {
            // The bytes model: the packed contour pass writes 16 bytes per vertex instead of 32.
            const json& separate = *measured["separate"];
            const json& packed = *measured["packed"];
            EXPECT_EQ(packed["mesh_vertices"], separate["mesh_vertices"]);
            EXPECT_DOUBLE_EQ(separate["bytes_per_step"].get<double>() - packed["bytes_per_step"].get<double>(),
                             16.0 * separate["mesh_vertices"].get<double>());
        }
    }
    ASSERT_EQ(d["copy_bandwidth"].size(), 1u);
    const json& c = d["copy_bandwidth"][0];
    EXPECT_EQ(c.value("backend", ""), backend);
    expect_number(c, "bytes_per_second", "copy_bandwidth");
    expect_number(c, "bytes", "copy_bandwidth");
    EXPECT_TRUE(c["method"].is_string());

    for (const char* key : {"settings", "presets", "forest", "copy_bandwidth"})
        expect_figures_positive(d[key], key);
}

}  // namespace

TEST_F(BenchCli, QuickCpuWritesSchemaAndTables) {
    BenchRun r;
    json d = quick("cpu", r);
    expect_schema(d, "cpu");
    EXPECT_NE(r.out.find("| preset | vertices | backend |"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("### Forest scaling"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("| backend | instances | layout |"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("| cpu | 20 | remove 1 |"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("| cpu | 20 | pause 2 |"), std::string::npos) << r.out;
    // Live control: removal and adding back within the capacity happen in place (no upload),
    // adding past the capacity uploads the scene once; pausing is timed.
    bool removal = false, growth = false, pause = false;
    for (const json& e : d["live_control"]) {
        if (e.contains("remove_seconds")) {
            removal = true;
            EXPECT_EQ(e.value("scene_uploads", 99), 0) << e.dump();
        }
        if (e.contains("add_past_capacity_seconds")) {
            growth = true;
            EXPECT_EQ(e.value("scene_uploads", 99), 1) << e.dump();
        }
        if (e.contains("pause_seconds")) {
            pause = true;
            EXPECT_GE(e.value("paused_step_seconds", -1.0), 0.0) << e.dump();
            EXPECT_GE(e.value("paused_steps_seconds", -1.0), 0.0) << e.dump();
        }
    }
    EXPECT_TRUE(removal && growth && pause) << d["live_control"].dump();
    // --render prints the same tables from the JSON.
    BenchRun rendered = run("bench --render " + (dir_ / "bench.json").string());
    EXPECT_EQ(rendered.exit_code, 0) << rendered.err;
    EXPECT_EQ(rendered.out, r.out);
}

/// cpu beside cpu-parallel: both in the schema; speed-ups over cpu and over the best CPU backend
/// of each case, the best being the faster of the two, with ratios consistent with the rates.
TEST_F(BenchCli, QuickCpuParallelReportsSpeedUpsOverCpuAndBestCpu) {
    BenchRun r;
    json d = quick("cpu,cpu-parallel", r);
    ASSERT_TRUE(d.is_object());
    std::map<std::string, json> by_backend;
    for (const char* backend : {"cpu", "cpu-parallel"}) {
        json only = d;
        for (const char* key : {"presets", "forest", "copy_bandwidth"}) {
            only[key] = json::array();
            for (const json& e : d[key])
                if (e.value("backend", "") == backend) only[key].push_back(e);
        }
        SCOPED_TRACE(backend);
        expect_schema(only, backend);
        by_backend[backend] = only["presets"][0];
    }
    const json& cpu = by_backend["cpu"];
    const json& parallel = by_backend["cpu-parallel"];
    for (const char* key : {"per_call", "batched", "readback"}) {
        const double serial_rate = cpu["steps_per_second"][key], parallel_rate = parallel["steps_per_second"][key];
        EXPECT_DOUBLE_EQ(cpu["speedup_over_cpu"][key].get<double>(), 1.0);
        EXPECT_DOUBLE_EQ(parallel["speedup_over_cpu"][key].get<double>(), parallel_rate / serial_rate);
        const std::string best = serial_rate >= parallel_rate ? "cpu" : "cpu-parallel";
        EXPECT_EQ(parallel["best_cpu"][key], best);
        EXPECT_DOUBLE_EQ(parallel["speedup_over_best_cpu"][key].get<double>(),
                         parallel_rate / std::max(serial_rate, parallel_rate));
    }
    EXPECT_NE(r.out.find("× best CPU batched"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find(" | cpu-parallel | "), std::string::npos) << r.out;
}

TEST_F(BenchCli, QuickVulkanWritesSchema) {
    const auto kinds = hmsm::compiled_backends();
    if (std::find(kinds.begin(), kinds.end(), hmsm::BackendKind::vulkan) == kinds.end())
        GTEST_SKIP() << "the Vulkan backend is not compiled into this build";
    BenchRun r;
    const std::string path = (dir_ / "bench.json").string();
    r = run("bench --quick --no-progress --backends cpu,vulkan --json " + path + " --commit test");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    json d = json::parse(slurp(path), nullptr, false);
    ASSERT_FALSE(d.is_discarded());
    for (const json& b : d["backends"])
        if (b.value("backend", "") == "vulkan" && !b.value("available", false))
            GTEST_SKIP() << "no Vulkan device: " << d["skipped"].dump();
    // Keep only the vulkan figures (speed-ups need the cpu run beside them) and check them.
    json only = d;
    for (const char* key : {"presets", "forest", "copy_bandwidth"}) {
        only[key] = json::array();
        for (const json& e : d[key])
            if (e.value("backend", "") == "vulkan") only[key].push_back(e);
    }
    expect_schema(only, "vulkan");
    expect_figures_positive(d["presets"], "presets");
}

TEST_F(BenchCli, BadArgumentsExitTwoWithOneLine) {
    for (const std::string args : {"bench --steps 0", "bench --backends cpu,metal", "bench --instances 1,x",
                                   "bench --presets paper-9 --instances none", "bench --render /nonexistent.json"}) {
        SCOPED_TRACE(args);
        BenchRun r = run(args + " --json " + (dir_ / "out.json").string());
        EXPECT_EQ(r.exit_code, 2) << r.err;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
        EXPECT_FALSE(fs::exists(dir_ / "out.json"));
    }
}
