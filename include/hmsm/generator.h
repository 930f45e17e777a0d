// Deterministic procedural trees and the paper presets (docs/model.md 6).
#pragma once

#include <hmsm/export.h>

#include <hmsm/tree.h>

#include <string_view>
#include <vector>

namespace hmsm {

/// Names of the presets: paper-1 ... paper-5.
HMSM_API const std::vector<std::string_view>& preset_names();

/// Generates preset `name` with `seed` (0 = the preset's own seed). The same name and seed give
/// the same tree on every platform.
HMSM_API Result<TreeModel> generate_preset(std::string_view name, uint64_t seed = 0);

}  // namespace hmsm
