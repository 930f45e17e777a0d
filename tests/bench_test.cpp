// `hmsm bench --quick` through the CLI binary: the JSON schema of docs/benchmarks/README.md, every
// figure finite and positive, the markdown on stdout, --render and the --out page agreeing. No timing
// thresholds.
#include "cli_fixture.h"

#include <hmsm/simulation.h>

#include <nlohmann/json.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

using hmsm::test::CliRun;
using hmsm::test::read_text;

class BenchCli : public hmsm::test::CliFixture {
protected:
    BenchCli() : CliFixture(/*small_tree=*/false) {}

    /// Runs the quick bench on one backend; returns its JSON document.
    json quick(const std::string& backend, CliRun& r) {
        const std::string file = path("bench.json");
        r = run("bench --quick --no-progress --backends " + backend + " --json " + file + " --commit test");
        EXPECT_EQ(r.exit_code, 0) << r.err;
        if (!fs::exists(file)) return json();
        json document = json::parse(read_text(file), nullptr, false);
        EXPECT_FALSE(document.is_discarded()) << "not JSON";
        return document;
    }
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
    CliRun r;
    json d = quick("cpu", r);
    expect_schema(d, "cpu");
    EXPECT_NE(r.out.find("| preset | vertices | backend |"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("### Forest scaling"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("| backend | instances | layout |"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("| cpu | 20 | remove 1 |"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("| cpu | 20 | pause 2 |"), std::string::npos) << r.out;
    // Live control: removal and adding back within the capacity happen in place (no upload),
    // adding past the capacity grows it once, on the device; pausing is timed.
    bool removal = false, growth = false, pause = false, lod = false;
    for (const json& e : d["live_control"]) {
        if (e.contains("remove_seconds")) {
            removal = true;
            EXPECT_EQ(e.value("scene_uploads", 99), 0) << e.dump();
        }
        if (e.contains("add_past_capacity_seconds")) {  // the CPU backends grow on the device
            growth = true;
            EXPECT_EQ(e.value("scene_uploads", 99), 0) << e.dump();
            EXPECT_EQ(e.value("device_growths", 99), 1) << e.dump();
        }
        if (e.contains("lod_coarser_seconds")) {  // switches within the capacity: no upload
            lod = true;
            EXPECT_EQ(e.value("scene_uploads", 99), 0) << e.dump();
            EXPECT_GT(e.value("lod_finer_seconds", -1.0), 0.0) << e.dump();
            EXPECT_GT(e.value("update_lod_unchanged_seconds", -1.0), 0.0) << e.dump();
        }
        if (e.contains("pause_seconds")) {
            pause = true;
            EXPECT_GE(e.value("paused_step_seconds", -1.0), 0.0) << e.dump();
            EXPECT_GE(e.value("paused_steps_seconds", -1.0), 0.0) << e.dump();
        }
    }
    EXPECT_TRUE(removal && growth && pause && lod) << d["live_control"].dump();
    EXPECT_NE(r.out.find("| cpu | 20 | switch 10 to 16 joints (set_instance_lods) |"), std::string::npos) << r.out;
    // --render prints the same tables from the JSON.
    CliRun rendered = run("bench --render " + (dir_ / "bench.json").string());
    EXPECT_EQ(rendered.exit_code, 0) << rendered.err;
    EXPECT_EQ(rendered.out, r.out);
}

/// cpu beside cpu-parallel: both in the schema; speed-ups over cpu and over the best CPU backend
/// of each case, the best being the faster of the two, with ratios consistent with the rates.
TEST_F(BenchCli, QuickCpuParallelReportsSpeedUpsOverCpuAndBestCpu) {
    CliRun r;
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
    CliRun r;
    const std::string path = (dir_ / "bench.json").string();
    r = run("bench --quick --no-progress --backends cpu,vulkan --json " + path + " --commit test");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    json d = json::parse(read_text(path), nullptr, false);
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
    for (const auto& [args, fragment] :
         {std::pair{"bench --steps 0", "--steps"}, std::pair{"bench --backends cpu,metal", "--backends 'metal'"},
          std::pair{"bench --instances 1,x", "--instances"},
          std::pair{"bench --presets paper-9 --instances none", "paper-9"},
          std::pair{"bench --render /nonexistent.json", "/nonexistent.json"}})
        expect_bad_input(std::string(args) + " --json " + path("out.json"), fragment);
}

/// --out STEM: the device page (a header with the device, commit and date, then the tables printed
/// on stdout) and the raw result beside it, replacing earlier files; --render --out writes the same
/// page from a saved result.
TEST_F(BenchCli, OutWritesTheDevicePageAndReplacesIt) {
    const fs::path stem = dir_ / "test-device";
    std::ofstream(stem.string() + ".md") << "an earlier page\n";
    std::ofstream(stem.string() + ".json") << "{}\n";
    const CliRun r = run("bench --quick --no-progress --backends cpu --presets none --instances none "
                         "--joint-instances 1 --commit abc1234 --out " + stem.string());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const json d = json::parse(read_text(stem.string() + ".json"), nullptr, false);
    ASSERT_FALSE(d.is_discarded());
    EXPECT_EQ(d.value("format", ""), "hmsm-bench");
    EXPECT_EQ(d.value("commit", ""), "abc1234");
    ASSERT_FALSE(d["forest_joints"].empty()) << d.dump();
    const std::string page = read_text(stem.string() + ".md");
    EXPECT_EQ(page.rfind("# hmsm bench: test-device\n", 0), 0u) << page;
    EXPECT_NE(page.find("commit abc1234, " + d.value("date", std::string("?"))), std::string::npos) << page;
    EXPECT_NE(page.find("[test-device.json](test-device.json)"), std::string::npos) << page;
    ASSERT_GE(page.size(), r.out.size());
    EXPECT_EQ(page.substr(page.size() - r.out.size()), r.out) << "the page's tables differ from stdout";
    EXPECT_EQ(page.find("an earlier page"), std::string::npos);
    EXPECT_FALSE(fs::exists(stem.string() + ".md.tmp-hmsm"));

    const fs::path copy = dir_ / "copy";
    const CliRun rendered = run("bench --render " + stem.string() + ".json --out " + copy.string());
    ASSERT_EQ(rendered.exit_code, 0) << rendered.err;
    EXPECT_EQ(rendered.out, r.out);
    EXPECT_EQ(read_text(copy.string() + ".json"), read_text(stem.string() + ".json"));
    const std::string copied_page = read_text(copy.string() + ".md");
    EXPECT_EQ(copied_page.rfind("# hmsm bench: copy\n", 0), 0u) << copied_page;
    EXPECT_EQ(copied_page.substr(copied_page.size() - r.out.size()), r.out);
}

TEST_F(BenchCli, OutWithAnExtensionOrAMissingFolderExitsTwoWritingNothing) {
    for (const std::string stem : {path("page.json"), path("page.md"), (dir_ / "absent" / "page").string()})
        expect_bad_input("bench --quick --backends cpu --out " + stem, "--out");
}

// The break-even measurement of Composition::automatic's depth rule: both compositions timed
// per depth and forest size.
TEST_F(BenchCli, CompositionDepthsTimesWalkAndJumping) {
    const std::string file = path("depths.json");
    const CliRun r = run("bench --no-progress --backends cpu --presets none --instances none --joint-instances none "
                     "--composition-depths 4,24 --steps 2 --warmup 1 --repeats 1 --case-budget 1 --json " + file);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const json d = json::parse(read_text(file), nullptr, false);
    ASSERT_TRUE(d.contains("composition_depths"));
    const json& rows = d["composition_depths"];
    ASSERT_EQ(rows.size(), 4u);  // 2 depths x 1 and 100 instances
    for (const json& row : rows) {
        EXPECT_FALSE(row.contains("failed")) << row.dump();
        expect_figures_positive(row["path_walk_ms"], "path_walk_ms");
        expect_figures_positive(row["pointer_jumping_ms"], "pointer_jumping_ms");
    }
    EXPECT_EQ(rows[2]["depth"], 24);
    EXPECT_NE(r.out.find("walk / jumping"), std::string::npos);
}

// The frame table on the CPU backends: per backend and forest size one row per change, in
// order, each with the frames run and call and frame times (median <= p99, call <= frame for a
// blocking step), and the markdown table.
TEST_F(BenchCli, FramesTableHasARowPerBackendSizeAndChange) {
    const std::string file = path("frames.json");
    const CliRun r = run("bench --no-progress --backends cpu,cpu-parallel --presets none --instances none "
                         "--joint-instances none --frames 12 --frame-instances 1,4 --case-budget 20 --json " + file);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const json d = json::parse(read_text(file), nullptr, false);
    ASSERT_TRUE(d.contains("frames"));
    const json& rows = d["frames"];
    // backends x sizes x (4 changes + 2 readbacks)
    ASSERT_EQ(rows.size(), 2u * 2u * 6u) << rows.dump();
    const char* changes[] = {"none", "set_wind", "moving_field", "stream_10", "readback_read", "readback_request_take"};
    for (size_t i = 0; i < rows.size(); ++i) {
        const json& row = rows[i];
        SCOPED_TRACE(row.dump());
        EXPECT_EQ(row["backend"], i < 12 ? "cpu" : "cpu-parallel");
        EXPECT_EQ(row["path"], "step");
        EXPECT_EQ(row["instances"], (i / 6) % 2 == 0 ? 1 : 4);
        EXPECT_EQ(row["change"], changes[i % 6]);
        ASSERT_FALSE(row.contains("skipped") || row.contains("failed"));
        EXPECT_GE(row.value("frames", 0), 10);
        EXPECT_LE(row.value("frames", 0), 12);
        for (const char* key : {"call_median_seconds", "call_p99_seconds", "frame_median_seconds", "frame_p99_seconds"})
            expect_figures_positive(row[key], key);
        EXPECT_LE(row["call_median_seconds"].get<double>(), row["call_p99_seconds"].get<double>());
        EXPECT_LE(row["frame_median_seconds"].get<double>(), row["frame_p99_seconds"].get<double>());
        EXPECT_LE(row["call_median_seconds"].get<double>(), row["frame_median_seconds"].get<double>());
        if (i % 6 == 3) EXPECT_EQ(row["streamed"], (i / 6) % 2 == 0 ? 1 : 4);  // all of a forest under 10
        if (i % 6 >= 4) EXPECT_GT(row.value("bytes", 0), 0);
        EXPECT_EQ(row.value("steps", 0), 1);
        EXPECT_FALSE(row.contains("device_median_seconds")) << "a blocking step has no engine marks";
    }
    EXPECT_NE(r.out.find("### Frames: one step per frame"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("| cpu-parallel | step | 4 | stream_10 |"), std::string::npos) << r.out;
    expect_bad_input("bench --quick --backends cpu --frames -1", "--frames");
    expect_bad_input("bench --quick --backends cpu --frames 10 --frame-steps 0", "--frame-steps");
}

// An engine's Vulkan frame of two steps: recorded into its command buffer between two
// timestamps of its own, whose difference each row gives as device time (at most the frame).
TEST_F(BenchCli, FramesTableTimesTheEngineFrameOnTheDevice) {
    const auto kinds = hmsm::compiled_backends();
    if (std::find(kinds.begin(), kinds.end(), hmsm::BackendKind::vulkan) == kinds.end())
        GTEST_SKIP() << "the Vulkan backend is not compiled into this build";
    const std::string file = path("frames.json");
    const CliRun r = run("bench --no-progress --backends vulkan --presets none --instances none --joint-instances none "
                         "--frames 10 --frame-instances 1 --frame-steps 2 --case-budget 20 --json " + file);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const json d = json::parse(read_text(file), nullptr, false);
    ASSERT_TRUE(d.contains("frames"));
    size_t recorded = 0;
    for (const json& row : d["frames"]) {
        SCOPED_TRACE(row.dump());
        if (row.contains("skipped")) GTEST_SKIP() << "no Vulkan device: " << row["skipped"];
        EXPECT_EQ(row.value("steps", 0), 2);
        if (row.value("path", "") != "record") continue;
        ++recorded;
        ASSERT_TRUE(row.contains("device_median_seconds"));
        expect_figures_positive(row["device_median_seconds"], "device_median_seconds");
        EXPECT_LE(row["device_median_seconds"].get<double>(), row["device_p99_seconds"].get<double>());
        EXPECT_LE(row["device_median_seconds"].get<double>(), row["frame_median_seconds"].get<double>());
    }
    EXPECT_EQ(recorded, 4u) << "one record row per change";
    EXPECT_NE(r.out.find("### Frames: 2 steps per frame"), std::string::npos) << r.out;
}
