// Random but consistent scene data for per-dispatch tests: chain trees ordered by depth, nodes,
// mesh vertices with fix-up chains, and instances of several models in several groups, with
// sizes that are not multiples of the workgroup size. Plus the dispatches of one pass.
#pragma once

#include "scene_data.h"
#include "backend.h"

#include <random>
#include <vector>

namespace hmsm::test {

struct ModelShape {
    uint32_t chains, nodes, vertices;
};

/// `instance_models[i]` is the model of instance i; runs of one model are split into groups of
/// at most `max_group_instances`.
detail::SceneData random_scene_data(std::mt19937& rng, const std::vector<ModelShape>& models,
                                    const std::vector<uint32_t>& instance_models,
                                    uint32_t max_group_instances);

/// How a pass's dispatches are composed in a per-dispatch check: pointer jumping in its two
/// dispatch forms (detail::JumpingForm), level by level, or the path walk. The values seed each
/// case's random scenes.
enum class PassForm : uint32_t { jump_per_round = 1, jump_in_dispatch = 2, level_by_level = 3, path_walk = 4 };
/// "pointer_jumping_per_round", "pointer_jumping_in_dispatch", "level_by_level", "path_walk".
const char* name_of(PassForm form);

/// Every variant of `pass` as separate dispatch lists (one dispatch per group each): one list
/// for a flat pass; for compose and root_positions one per pointer-jumping round, one with every
/// round in one dispatch (PassForm::jump_in_dispatch), or one per level. Ping-pong halves of
/// single rounds and levels are drawn from `rng`.
std::vector<std::vector<detail::Dispatch>> pass_variants(const detail::SceneData& d, Pass pass, PassForm form,
                                                         std::mt19937& rng);

/// A wind-table step slot, uniform in [0, HMSM_WIND_STEP_SLOTS).
/// A random wind-table step slot (Backend::run's per-step argument).
uint32_t uniform_wind_slot(std::mt19937& rng);

/// Writes the same random state (angles in range, rotations, positions) to both backends.
void randomize_state(const detail::SceneData& d, detail::Backend& a, detail::Backend& b,
                     std::mt19937& rng);

}  // namespace hmsm::test
