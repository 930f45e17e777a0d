#include "bench_depth.h"

#include <algorithm>
#include <chrono>
#include <cstdio>

namespace hmsm::cli::bench {
namespace {

using Clock = std::chrono::steady_clock;

/// A rod of depth + 1 nodes; with ModelOptions::max_chain_segments = 1 every segment is a chain
/// of its own, the child of the one below: chain depths 0 .. depth - 1.
TreeModel deep_rod(uint32_t depth) {
    TreeModel tree;
    const double length = 0.1;
    for (uint32_t i = 0; i <= depth; ++i) {
        const double radius = 0.05 * (1.0 - 0.9 * double(i) / double(depth + 1));
        tree.nodes.push_back({int32_t(i) - 1, glm::dvec3(0.0, length * double(i), 0.0), radius});
    }
    return tree;
}

}  // namespace

Result<double> wall_seconds_per_step(Simulation& sim, uint32_t steps, uint32_t warmup, double budget) {
    HMSM_TRY(sim.step(std::max(1u, warmup)));
    auto start = Clock::now();
    HMSM_TRY(sim.step(1));
    const double probe = std::chrono::duration<double>(Clock::now() - start).count();
    const uint32_t timed = uint32_t(std::clamp(budget / std::max(probe, 1e-9), 1.0, double(steps)));
    start = Clock::now();
    HMSM_TRY(sim.step(timed));
    return std::chrono::duration<double>(Clock::now() - start).count() / double(timed);
}

nlohmann::json measure_composition_depths(const std::vector<BackendKind>& backends,
                                          const std::vector<uint32_t>& depths, uint32_t steps,
                                          uint32_t warmup, double case_budget) {
    nlohmann::json rows = nlohmann::json::array();
    for (BackendKind kind : backends)
        for (uint32_t depth : depths)
            for (uint32_t instances : {1u, 100u}) {
                auto scene = grid_scene(deep_rod(depth), instances, 2.0, 1);
                if (!scene) continue;
                nlohmann::json row = {{"backend", to_string(kind)}, {"depth", depth}, {"instances", instances}};
                for (Composition composition : {Composition::path_walk, Composition::pointer_jumping}) {
                    SimulationConfig config;
                    config.backend = kind;
                    config.composition = composition;
                    config.outputs = Outputs::joints;
                    config.model.max_chain_segments = 1;
                    config.wind.profile = WindProfile::y1;
                    auto sim = Simulation::create(*scene, config);
                    Result<double> seconds = sim ? wall_seconds_per_step(**sim, steps, warmup, case_budget / 2)
                                                 : Result<double>(sim.status());
                    if (!seconds) {
                        row["failed"] = seconds.status().message();
                        break;
                    }
                    row["device"] = (*sim)->device_name();
                    row[std::string(to_string(composition)) + "_ms"] = *seconds * 1e3;
                }
                rows.push_back(row);
            }
    return rows;
}

std::string render_composition_depths(const nlohmann::json& rows) {
    if (!rows.is_array() || rows.empty()) return "";
    std::string out =
        "\n### Path walk against pointer jumping by hierarchy depth (joints only, ms of wall time per step)\n\n"
        "| backend | depth | instances | path_walk | pointer_jumping | walk / jumping |\n"
        "|---|--:|--:|--:|--:|--:|\n";
    for (const nlohmann::json& r : rows) {
        const std::string head = "| " + r.value("backend", std::string()) + " | " +
                                 std::to_string(r.value("depth", 0u)) + " | " +
                                 std::to_string(r.value("instances", 0u)) + " | ";
        if (r.contains("failed")) {
            out += head + r.value("failed", std::string()) + " | | |\n";
            continue;
        }
        const double walk = r.value("path_walk_ms", 0.0), jumping = r.value("pointer_jumping_ms", 0.0);
        char cells[96];
        std::snprintf(cells, sizeof cells, "%.3f | %.3f | %.2f", walk, jumping, jumping > 0 ? walk / jumping : 0.0);
        out += head + cells + " |\n";
    }
    return out;
}

}  // namespace hmsm::cli::bench
