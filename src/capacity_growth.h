// Growing the capacity-sized buffers on the device (Backend::grow): which buffers a growth
// reallocates, and the copies that carry their live elements from the old allocation into the
// new one. Every backend that grows in place takes its copies and zero ranges from here, so
// that the layout after a growth is the one an upload with the new capacities would give.
#pragma once

#include "buffers.h"
#include "scene_data.h"

#include <algorithm>
#include <cstdint>
#include <limits>
#include <vector>

namespace hmsm::detail {

/// Most elements of one state buffer a capacity grows to (a chain buffer holds two halves).
inline constexpr uint64_t kMaxStateElements = std::numeric_limits<uint32_t>::max() / 2;
/// Most instances an instance capacity grows to by itself (reserve_instances may ask for more).
inline constexpr uint64_t kMaxGrownInstances = uint64_t(1) << 24;

/// Capacity after growing to hold `needed`: 1.5 times the current one (or `needed`, if more),
/// never past `limit` unless `needed` is. Geometric growth makes a sequence of adds cost O(1)
/// amortized: n instances added one at a time grow the capacity O(log n) times, and the copies
/// of all growths together move fewer than 3 n instances' elements.
inline uint64_t grown_capacity(uint64_t current, uint64_t needed, uint64_t limit) {
    if (needed <= current) return current;
    return std::max(needed, std::min(limit, current + current / 2));
}

/// Whether a growth of the capacities reallocates buffer `id`: the state and output buffers
/// (chain, node and vertex scope) and the instance buffers. Model-scope buffers and the wind
/// table keep their allocation and contents.
constexpr bool sized_by_capacity(BufferId id) {
    const Scope s = buffer_info(id).scope;
    return s == Scope::chain || s == Scope::chain_halves || s == Scope::node || s == Scope::vertex ||
           s == Scope::instance;
}

/// The live elements of buffer `id` under `scene`'s live counts, per half of a ping-pong buffer:
/// the chains, nodes, vertices (up to the last slot held, in the placed layout) or instances
/// the scene holds now.
inline uint64_t live_elements(const SceneData& scene, BufferId id) {
    switch (buffer_info(id).scope) {
        case Scope::chain:
        case Scope::chain_halves: return scene.chains_held();
        case Scope::node: return scene.nodes_held();
        case Scope::vertex: return scene.vertices_held();
        case Scope::instance: return scene.instance_count();
        default: return 0;
    }
}

/// Elements [src, src + count) of the old allocation go to [dst, dst + count) of the new one.
struct GrowthCopy {
    uint64_t src = 0, dst = 0, count = 0;
};
/// Elements [first, first + count) of the new allocation are set to zero.
struct GrowthZero {
    uint64_t first = 0, count = 0;
};

/// How buffer `id` goes from `old_count` to `new_count` elements (its element_count under the
/// old and the new capacities) keeping its first `live` elements of each half: one copy per
/// half (the halves of a ping-pong buffer lie old_count / 2 and new_count / 2 elements apart,
/// so the second half moves), and the elements past the live ones zeroed, as an upload leaves
/// them. Empty where the buffer keeps its size.
struct GrowthPlan {
    std::vector<GrowthCopy> copies;
    std::vector<GrowthZero> zeros;
    bool reallocates = false;
};
inline GrowthPlan growth_plan(BufferId id, uint64_t old_count, uint64_t new_count, uint64_t live) {
    GrowthPlan plan;
    if (!sized_by_capacity(id) || new_count == old_count) return plan;
    plan.reallocates = true;
    const uint64_t halves = halves_of(id);
    const uint64_t old_half = old_count / halves, new_half = new_count / halves;
    const uint64_t kept = std::min({live, old_half, new_half});
    for (uint64_t h = 0; h < halves; ++h) {
        if (kept > 0) plan.copies.push_back({h * old_half, h * new_half, kept});
        if (new_half > kept) plan.zeros.push_back({h * new_half + kept, new_half - kept});
    }
    return plan;
}

}  // namespace hmsm::detail
