// The step program: the dispatches of the seven passes over every instance group, in the
// order of the pass table (pass_table.h), for one composition (docs/model.md 3.7).
#pragma once

#include "backend.h"
#include "scene_data.h"

#include <hmsm/pass.h>
#include <hmsm/simulation.h>

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
/// composes by the walk that integrates ahead (gpu_layout.h HMSM_DISPATCH_WALK_AHEAD).
std::vector<Dispatch> build_program(const SceneData& d, const std::vector<InstanceGroup>& groups,
                                    Composition composition, bool dispatches_are_expensive,
                                    Pass first, uint32_t passes, bool walk_ahead = false);

}  // namespace hmsm::detail
