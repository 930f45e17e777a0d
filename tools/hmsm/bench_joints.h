// hmsm bench: joints-only forest rows (docs/model.md 7, 3.10): forests stepped with
// SimulationConfig::outputs = joints (passes 1-5), whose cost scales with chains, not vertices.
#pragma once

#include "bench_measure.h"

#include <hmsm/hmsm.h>

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace hmsm::cli::bench {

/// One forest of joints-only rows: `count` instances of `model_name` on a grid.
struct JointForestCase {
    std::string model_name;
    TreeModel tree;
    uint32_t count = 0;
};

/// Measures every case on `backend` (cases in increasing size; a size whose extrapolated time
/// passes the case budget, or that needs more host memory than is available for a host-memory
/// backend, is skipped). Rows go to `rows` (section "forest_joints" of the JSON), skips and
/// failures to `skipped`; returns the number of failures.
int joint_forest_cases(BackendKind backend, const std::vector<JointForestCase>& cases, double spacing,
                       const Settings& settings, Progress& progress, nlohmann::json& rows,
                       nlohmann::json& skipped);

/// The markdown table of the joints-only rows ("" when there are none).
std::string render_joint_forest(const nlohmann::json& rows);

}  // namespace hmsm::cli::bench
