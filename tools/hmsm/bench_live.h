// hmsm bench: the cost of live control (docs/model.md 3.9) on a forest.
#pragma once

#include <hmsm/hmsm.h>

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace hmsm::cli::bench {

/// Per available backend: seconds to remove and to add back 1 and 100 instances of a forest of
/// `forest` trees of `model` (and whether the scene was uploaded anew), of switching 1, 10 and
/// 100 of them to 16 joints and back (levels of detail {256, 64, 16, 1}) and of an update_lod
/// with nothing to switch, of one set_wind + step
/// against a plain step, of pausing and resuming a tenth of the forest, and of adding past and
/// then within the capacity. One JSON object per backend and case; a backend that cannot hold
/// the forest is reported as skipped.
nlohmann::json measure_live_control(const TreeModel& model, const std::vector<BackendKind>& backends,
                                    uint32_t forest, double spacing);

/// The markdown table of measure_live_control's results ("" when there are none).
std::string render_live_control(const nlohmann::json& rows);

}  // namespace hmsm::cli::bench
