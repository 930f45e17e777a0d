// `hmsm bench --open-world` through the CLI binary on the serial CPU backend at a small size:
// the row's fields, level shares near the asked ones, a finite pop against a moving tree, call
// distributions in order, the memory estimate and the markdown; on Vulkan also the frames
// through the engine's path. No timing thresholds.
#include "cli_fixture.h"

#include <hmsm/simulation.h>

#include <nlohmann/json.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

using nlohmann::json;

namespace {

using hmsm::test::CliRun;
using hmsm::test::read_text;

class BenchOpenWorld : public hmsm::test::CliFixture {
protected:
    BenchOpenWorld() : CliFixture(/*small_tree=*/false) {}

    /// Runs `hmsm bench` with the open world alone on `backend`, `sizes` its --open-world-*
    /// flags, into `r`; returns the one open-world row of its JSON (null, the failure reported,
    /// where there is none).
    json open_world_row(const std::string& backend, const std::string& sizes, CliRun& r) {
        const std::string file = path("open_world_" + backend + ".json");
        r = run("bench --no-progress --backends " + backend +
                " --presets none --instances none --joint-instances none " + sizes + " --json " + file);
        EXPECT_EQ(r.exit_code, 0) << r.err;
        const json d = json::parse(read_text(file), nullptr, false);
        const bool one = d.is_object() && d.contains("open_world") && d["open_world"].size() == 1;
        EXPECT_TRUE(one) << d.dump();
        return one ? d["open_world"][0] : json();
    }
};

double number(const json& j, const char* key) {
    EXPECT_TRUE(j.is_object() && j.contains(key) && j[key].is_number()) << "no number '" << key << "' in " << j.dump();
    return j.is_object() && j.contains(key) && j[key].is_number() ? j[key].get<double>() : std::nan("");
}

TEST_F(BenchOpenWorld, SmallWorldOnCpuReportsCallsSharesPopAndMemory) {
    const uint32_t trees = 1000, frames = 4;
    CliRun r;
    const json row = open_world_row(
        "cpu", "--open-world-trees 1000 --open-world-frames 4 --open-world-changes 40 --open-world-fade-bound 0", r);
    ASSERT_FALSE(row.is_null());
    SCOPED_TRACE(row.dump());
    ASSERT_FALSE(row.contains("skipped") || row.contains("failed"));
    EXPECT_EQ(row["backend"], "cpu");
    EXPECT_EQ(number(row, "fade_bound_m"), 0.0);
    EXPECT_EQ(row["model"], "paper-1");
    EXPECT_EQ(row["frames"], frames);
    // About `trees` within the radius (the lattice points of a disc of that area).
    EXPECT_NEAR(number(row, "instances"), trees, 0.05 * trees);
    EXPECT_GT(number(row["changes_per_frame"], "median"), 0.0);

    // Levels 0..4 hold about 0.5 %, 2 %, 10 % and the rest, split between 16 joints and the trunk.
    const json& shares = row["level_shares"];
    const json& asked = row["level_shares_asked"];
    ASSERT_EQ(shares.size(), 5u);
    double sum = 0.0;
    for (size_t k = 0; k < 5; ++k) {
        sum += shares[k].get<double>();
        EXPECT_NEAR(shares[k].get<double>(), asked[k].get<double>(), 0.01 + 0.25 * asked[k].get<double>())
            << "level " << k;
    }
    EXPECT_NEAR(sum, 1.0, 1e-9);

    // Per call: median <= p99 <= max; update_lod and step once per frame.
    for (const char* call : {"update_lod", "swap_remove", "add", "step", "frame"}) {
        const json& c = row["calls"][call];
        SCOPED_TRACE(call);
        ASSERT_GT(c.value("calls", 0), 0);
        EXPECT_LE(number(c, "median_seconds"), number(c, "p99_seconds"));
        EXPECT_LE(number(c, "p99_seconds"), number(c, "max_seconds"));
    }
    EXPECT_EQ(row["calls"]["step"]["calls"], frames);
    EXPECT_EQ(row["calls"]["update_lod"]["calls"], frames);
    EXPECT_GT(number(row["still"]["step"], "median_seconds"), 0.0);
    // The standing frames are timed after the moving frames' fades have ended: they change nothing.
    EXPECT_EQ(row.value("fading_after_settling", -1), 0);
    EXPECT_TRUE(std::isfinite(number(row, "changes_add_seconds")));

    // The pop: switched trees measured, a finite jump, and a tree that moved over the frame.
    const json& pop = row["pop"];
    EXPECT_GT(pop.value("switches_measured", 0), 0) << pop.dump();
    EXPECT_TRUE(std::isfinite(number(pop, "largest_jump_m")));
    EXPECT_GE(number(pop, "largest_jump_m"), 0.0);
    EXPECT_GT(number(pop, "motion_of_largest_m"), 0.0);
    EXPECT_GT(number(pop, "median_motion_m"), 0.0);
    ASSERT_FALSE(pop["by_switch"].empty());
    int measured = 0;
    for (const auto& [kind, entry] : pop["by_switch"].items()) {
        measured += entry.value("measured", 0);
        EXPECT_LE(number(entry, "largest_jump_m"), number(pop, "largest_jump_m")) << kind;
    }
    EXPECT_EQ(measured, pop.value("switches_measured", -1));

    // Bytes per step against the copy roofline.
    EXPECT_GT(number(row, "bytes_per_step"), 0.0);
    EXPECT_GT(number(row, "copy_bandwidth"), 0.0);
    EXPECT_GT(number(row, "copy_bandwidth_fraction"), 0.0);

    // Memory: the estimate at the asked shares lies below that of as many whole trees, and the
    // allocation after the run is of the estimate's order. Every level keeps the model's mesh
    // vertices; its state keeps only its chains' attach nodes (joints only), one for the trunk
    // alone, which bound the tree count.
    const json& memory = row["memory"];
    EXPECT_GT(number(memory, "estimate_device_bytes"), 0.0);
    EXPECT_LT(number(memory, "estimate_device_bytes"), number(memory, "estimate_whole_trees_device_bytes"));
    EXPECT_LT(number(row["memory_after"], "device_bytes"), 3.0 * number(memory, "estimate_device_bytes"));
    ASSERT_EQ(memory["levels"].size(), 5u);
    EXPECT_EQ(memory["levels"][0]["chains"], 2345);
    EXPECT_EQ(memory["levels"][4]["chains"], 1);
    EXPECT_EQ(memory["levels"][4]["nodes"], 1);
    EXPECT_LE(memory["levels"][3]["nodes"].get<uint64_t>(), 16u);
    EXPECT_LT(memory["levels"][0]["nodes"].get<uint64_t>(), 2345u);
    EXPECT_EQ(memory["levels"][4]["mesh_vertices"], memory["levels"][0]["mesh_vertices"]);
    EXPECT_EQ(number(memory, "largest_trees_by_nodes"),
              double(std::numeric_limits<uint32_t>::max() / memory["levels"][0]["nodes"].get<uint64_t>()));
    EXPECT_EQ(number(memory, "largest_trees_by_mesh_vertices"),
              double(std::numeric_limits<uint32_t>::max() / memory["levels"][0]["mesh_vertices"].get<uint64_t>()));

    // Coarsening switches fade by default; the pop reports the switches and the fading trees.
    EXPECT_EQ(row["fade_steps"], hmsm::LodBands{}.fade_steps);
    EXPECT_GE(number(row["pop"], "fading_trees_measured"), 0.0);
    EXPECT_GE(number(row["pop"], "switches_measured"), 0.0);

    EXPECT_NE(r.out.find("### Open world"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("| cpu | update_lod | 4 |"), std::string::npos) << r.out;
}

// On a backend with an engine path (Vulkan: record_steps) the open world also moves through
// that path: the changes and the recorded step per frame, with their own distributions and
// rows in the markdown.
TEST_F(BenchOpenWorld, VulkanAlsoMovesThroughTheEnginesPath) {
    const auto kinds = hmsm::compiled_backends();
    if (std::find(kinds.begin(), kinds.end(), hmsm::BackendKind::vulkan) == kinds.end())
        GTEST_SKIP() << "the Vulkan backend is not compiled into this build";
    CliRun r;
    const json row = open_world_row("vulkan", "--open-world-trees 200 --open-world-frames 3 --open-world-changes 10", r);
    ASSERT_FALSE(row.is_null());
    SCOPED_TRACE(row.dump());
    if (row.contains("skipped") || row.contains("failed"))
        GTEST_SKIP() << "no Vulkan device: " << row.value("skipped", row.value("failed", std::string()));
    ASSERT_TRUE(row.contains("engine_moving") && row["engine_moving"].size() == 1);
    const json& engine = row["engine_moving"][0];
    EXPECT_EQ(engine["path"], "record");
    const json& calls = engine["calls"];
    EXPECT_EQ(calls["update_lod"]["calls"], 3);
    EXPECT_EQ(calls["frame"]["calls"], 3);
    EXPECT_GT(number(calls["frame"], "median_seconds"), 0.0);
    EXPECT_GE(number(calls["frame"], "median_seconds"), number(calls["changes_and_step_call"], "median_seconds"));
    EXPECT_TRUE(std::isfinite(number(engine, "changes_add_seconds")));
    // The room reserved by level before the world streamed in holds every frame's changes.
    ASSERT_TRUE(row.contains("reserved_per_level") && row["reserved_per_level"].size() == 5);
    EXPECT_GE(row["reserved_per_level"][4].get<double>(), 2 * 0.4375 * 200);
    EXPECT_EQ(number(row, "device_growths"), 0.0);
    EXPECT_EQ(number(engine, "device_growths"), 0.0);
    EXPECT_EQ(number(engine, "scene_uploads"), 0.0);
    EXPECT_NE(r.out.find("| vulkan (record) | update_lod | 3 |"), std::string::npos) << r.out;
}

TEST_F(BenchOpenWorld, BadSizesExitTwoWithOneLine) {
    expect_bad_input("bench --backends cpu --presets none --open-world-trees 0", "--open-world-trees");
    expect_bad_input("bench --backends cpu --presets none --open-world-frames 0", "--open-world-frames");
    expect_bad_input("bench --backends cpu --presets none --open-world-trees 10 --open-world-changes 11",
                     "--open-world-changes");
    expect_bad_input("bench --backends cpu --presets none --open-world-fade-steps -1", "--open-world-fade-steps");
    expect_bad_input("bench --backends cpu --presets none --open-world-fade-steps 70000", "--open-world-fade-steps");
    expect_bad_input("bench --backends cpu --presets none --open-world-fade-bound -0.1", "--open-world-fade-bound");
    expect_bad_input("bench --backends cpu --presets none --open-world-fade-bound 2", "--open-world-fade-bound");
}

}  // namespace
