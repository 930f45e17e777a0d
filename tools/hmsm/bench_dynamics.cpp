#include "bench_dynamics.h"

#include "bench_depth.h"

#include <cstdio>

namespace hmsm::cli::bench {

nlohmann::json measure_dynamics(const TreeModel& tree, const std::string& model_name,
                                const std::vector<BackendKind>& backends, uint32_t forest_count, double spacing,
                                uint32_t steps, uint32_t warmup, double case_budget) {
    nlohmann::json rows = nlohmann::json::array();
    struct Case {
        uint32_t instances;
        Outputs outputs;
    };
    for (BackendKind kind : backends)
        for (const Case& c : {Case{1, Outputs::all}, Case{forest_count, Outputs::joints}}) {
            auto scene = c.instances == 1 ? Result<Scene>(single_tree_scene(tree))
                                          : grid_scene(tree, c.instances, spacing, 1);
            nlohmann::json row = {{"backend", to_string(kind)}, {"model", model_name},
                                  {"instances", c.instances}, {"outputs", to_string(c.outputs)}};
            if (!scene) {
                row["failed"] = scene.status().message();
                rows.push_back(row);
                continue;
            }
            struct Variant {
                const char* name;
                Dynamics dynamics;
                Exchange exchange;
            };
            for (const Variant& v : {Variant{"paper", Dynamics::paper, Exchange::held},
                                     Variant{"coupled", Dynamics::coupled, Exchange::held},
                                     Variant{"articulated", Dynamics::coupled, Exchange::articulated}}) {
                SimulationConfig config;
                config.backend = kind;
                config.outputs = c.outputs;
                config.model.dynamics = v.dynamics;
                config.model.exchange = v.exchange;
                config.wind.profile = WindProfile::y1;
                auto sim = Simulation::create(*scene, config);
                Result<double> seconds = sim ? wall_seconds_per_step(**sim, steps, warmup, case_budget / 3)
                                             : Result<double>(sim.status());
                if (!seconds) {
                    row["failed"] = std::string(v.name) + ": " + seconds.status().message();
                    break;
                }
                row["device"] = (*sim)->device_name();
                row[std::string(v.name) + "_ms"] = *seconds * 1e3;
            }
            rows.push_back(row);
        }
    return rows;
}

std::string render_dynamics(const nlohmann::json& rows) {
    if (!rows.is_array() || rows.empty()) return "";
    std::string out =
        "\n### The coupled dynamics beside the paper's (ms of wall time per step)\n\n"
        "| backend | model | instances | outputs | paper | coupled | coupled / paper | articulated | "
        "articulated / paper |\n"
        "|---|---|--:|---|--:|--:|--:|--:|--:|\n";
    for (const nlohmann::json& r : rows) {
        const std::string head = "| " + r.value("backend", std::string()) + " | " + r.value("model", std::string()) +
                                 " | " + std::to_string(r.value("instances", 0u)) + " | " +
                                 r.value("outputs", std::string()) + " | ";
        if (r.contains("failed")) {
            out += head + r.value("failed", std::string()) + " | | | | |\n";
            continue;
        }
        const double paper = r.value("paper_ms", 0.0), coupled = r.value("coupled_ms", 0.0);
        char cells[160];
        std::snprintf(cells, sizeof cells, "%.3f | %.3f | %.2f", paper, coupled, paper > 0 ? coupled / paper : 0.0);
        out += head + cells;
        const double articulated = r.value("articulated_ms", 0.0);
        std::snprintf(cells, sizeof cells, " | %.3f | %.2f |\n", articulated, paper > 0 ? articulated / paper : 0.0);
        out += cells;
    }
    return out;
}

}  // namespace hmsm::cli::bench
