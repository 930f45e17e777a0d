// The step program: the dispatches of the seven passes over every instance group, in the
// order of the pass table (pass_table.h), for one composition mode (docs/model.md 3.7).
#pragma once

#include "backend.h"
#include "scene_data.h"

#include <hmsm/pass.h>
#include <hmsm/config.h>

#include <cstdint>
#include <vector>

namespace hmsm::detail {

/// Whether Composition::pointer_jumping runs a group's rounds in one dispatch (step_program.cpp
/// gives the measurements behind the rule).
bool rounds_in_dispatch_pay(uint32_t instances, uint32_t chains, bool dispatches_are_expensive);

/// Appends the dispatches of `pass` for every group.
void append_pass(std::vector<Dispatch>& program, const SceneData& d,
                 const std::vector<InstanceGroup>& groups, Pass pass, Composition composition,
                 bool dispatches_are_expensive);

/// The program of the passes from `first` on whose bit is set in `passes`, less the passes
/// whose outputs the scene does not produce (outputs on demand). `walk_ahead`
/// (Backend::walks_ahead): a path-walk step of a forest whose every instance is active
/// composes by the walk that integrates ahead (gpu_layout.h HMSM_WALK_AHEAD).
std::vector<Dispatch> build_program(const SceneData& d, const std::vector<InstanceGroup>& groups,
                                    Composition composition, bool dispatches_are_expensive,
                                    Pass first, uint32_t passes, bool walk_ahead = false);

/// Deepest hierarchy (chain depth levels below the trunk) for which Composition::automatic keeps
/// the path walk on a backend that prefers it: the walk costs depth-many products per chain, the
/// rounds of pointer jumping log2 of the depth, so past a break-even depth the rounds win. A
/// conservative first value, to be measured on the H100 (`hmsm bench --composition-depths`).
inline constexpr int32_t kPathWalkMaxDepth = 64;

/// What Composition::automatic resolves to: the path walk where the backend prefers it and no
/// model is deeper than kPathWalkMaxDepth, else pointer jumping.
Composition automatic_composition(bool backend_prefers_path_walk, int32_t deepest_chain_depth);

}  // namespace hmsm::detail
