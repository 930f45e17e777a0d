// hmsm bench --composition-depths: the path walk against pointer jumping on hierarchies of
// growing depth, to place Composition::automatic's break-even depth (src/step_program.h,
// kPathWalkMaxDepth; docs/architecture.md).
#pragma once

#include <hmsm/hmsm.h>

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace hmsm::cli::bench {

/// Wall seconds per step of `sim`: `warmup` steps (at least one), one probe step, then up to
/// `steps` timed steps in one call, fewer where the probe times the count would pass `budget`.
Result<double> wall_seconds_per_step(Simulation& sim, uint32_t steps, uint32_t warmup, double budget);

/// Per available backend, depth and forest size (1 and 100 instances): wall milliseconds per
/// step (joints only) of Composition::path_walk and of Composition::pointer_jumping on a
/// synthetic chain of `depth` levels (a straight rod cut into one-segment chains, each the
/// child of the one below). About `steps` timed steps each after `warmup`, fewer where one
/// step times the count would pass `case_budget` seconds.
nlohmann::json measure_composition_depths(const std::vector<BackendKind>& backends,
                                          const std::vector<uint32_t>& depths, uint32_t steps,
                                          uint32_t warmup, double case_budget);

/// The markdown table of measure_composition_depths' results ("" when there are none).
std::string render_composition_depths(const nlohmann::json& rows);

}  // namespace hmsm::cli::bench
