// Listed groups: the step program of a fragmented scene as one group per model. A streaming
// world's instances end up in index order on mixed levels (a swap removal moves the last tree
// into each hole, arrivals are appended and switch in place), so the runs of neighbours of one
// model — the contiguous groups — grow with the instances, and so would the dispatches. A listed
// group instead covers every active instance of one model wherever it lies: its dispatches read
// each instance's state offsets and index from the instance table (gpu_layout.h
// PassConstants.instance_list), so the program has a few dispatches per pass whatever the order.
#pragma once

#include "instance_placements.h"
#include "scene_data.h"

#include <hmsm/scene.h>

#include <cstdint>
#include <span>
#include <vector>

namespace hmsm::detail {

/// The listed groups of a program and the instance table they index.
struct ListedGroups {
    std::vector<InstanceGroup> groups;
    /// Per entry (chain_begin, node_begin, vertex_begin, instance), 4 scalars an entry, as
    /// Backend::write takes them for BufferId::instance_table.
    std::vector<double> table;
    uint32_t entries() const { return uint32_t(table.size() / 4); }
};

/// Appends the listed groups of model `model`'s entries [begin, end) of a table, split so that
/// no dispatch exceeds kMaxGroupElements threads.
void append_listed_groups(const SceneData& d, uint32_t model, uint32_t begin, uint32_t end,
                          std::vector<InstanceGroup>& into);

/// Whether a scene can be listed at all: every state offset and instance index fits the
/// table's 32-bit signed words.
bool scene_can_be_listed(const SceneData& d);

/// The listed groups of the active instances that `groups` (contiguous groups of d, as the step
/// program takes them; a group may cover paused instances, which are left out) cover: per
/// model, its instances in ascending index, split so that no dispatch exceeds
/// kMaxGroupElements threads; models in ascending order. O(instances covered + models). The
/// entries' state offsets are the groups' (the packed layout) or, given `placed`, each
/// instance's slot (the placed layout, instance_placements.h; the groups' offsets unused).
void list_groups(const SceneData& d, std::span<const InstanceGroup> groups, std::span<const Instance> instances,
                 ListedGroups& into, const InstancePlacements* placed = nullptr);

/// The listed groups of the instances `indices` (each once, active or paused) at their slots
/// `placed`: per model in ascending order, its instances in the order given, split so that no
/// dispatch exceeds kMaxGroupElements threads. O(indices + models).
void list_instances(const SceneData& d, std::span<const uint32_t> indices, std::span<const Instance> instances,
                    const InstancePlacements& placed, ListedGroups& into);

/// Whether the step program should run `listed` groups rather than the `contiguous` ones:
/// there are many contiguous groups (at least kListedGroupsFrom) and at least four times as
/// many as listed ones. HMSM_LIST_INSTANCES=0 in the environment (read once) never lists, =1
/// always lists where the backend can; set_listing_for_tests overrides both.
bool listing_pays(size_t contiguous, size_t listed);
inline constexpr size_t kListedGroupsFrom = 64;

/// Test hook: -1 (default) as the environment says, 0 never, 1 always, 2 by size whatever the
/// environment says.
void set_listing_for_tests(int mode);

}  // namespace hmsm::detail
