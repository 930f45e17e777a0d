// hmsm bench --dynamics coupled: the coupled dynamics (docs/model.md 3.13), with either exchange,
// beside the paper's,
// per step, on one tree with every output and on a joints-only forest.
#pragma once

#include <hmsm/hmsm.h>

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace hmsm::cli::bench {

/// Per available backend: wall milliseconds per step under Dynamics::paper, Dynamics::coupled
/// and coupled with Exchange::articulated of one `tree` with every output, and of
/// `forest_count` joints-only instances of it on a grid
/// `spacing` apart (outputs joints, passes 1-5). About `steps` timed steps each after `warmup`,
/// fewer where one step times the count would pass `case_budget` seconds.
nlohmann::json measure_dynamics(const TreeModel& tree, const std::string& model_name,
                                const std::vector<BackendKind>& backends, uint32_t forest_count, double spacing,
                                uint32_t steps, uint32_t warmup, double case_budget);

/// The markdown table of measure_dynamics' rows, with coupled / paper ("" when there are none).
std::string render_dynamics(const nlohmann::json& rows);

}  // namespace hmsm::cli::bench
