// What an instance carries when the instance list changes, and the moves that carry it on the
// device: the chain-scope state every change keeps (live_reshape.cpp, lod_switch.cpp), the
// outputs that move with it, and the moves of a change that keeps every instance's index but
// gives some of them another size (a level-of-detail switch): the instances between two
// resized ones keep their elements and shift by what the resized ones before them gained or
// lost, so each run of them is one move, and runs shift up or down by different amounts.
#pragma once

#include "backend.h"
#include "scene_data.h"

#include <algorithm>
#include <cstdint>
#include <iterator>
#include <span>
#include <vector>

namespace hmsm::detail {

/// The chain-scope state an instance carries: S, V, g, T, the joint matrices and both halves
/// of R and O. Nodes and vertices are recomputed from R and O.
/// The held exchange of the coupled dynamics adds the loads of the last step (docs/model.md 3.13;
/// `loads`: SceneData::holds_loads).
inline std::vector<BufferId> carried_buffers(bool loads) {
    std::vector<BufferId> ids = {BufferId::chain_state, BufferId::chain_force, BufferId::chain_local,
                                 BufferId::joint_matrix, BufferId::chain_rotation, BufferId::chain_origin};
    if (loads) ids.push_back(BufferId::chain_load);
    return ids;
}

/// The outputs that passes 6 and 7 compute from R and O, element for element: they move with
/// the state of an instance that changes place, bitwise what they were. node_relative (u,
/// pass 4) does not: it is scratch within a step, which pass 4 writes before passes 5 and 6 read
/// it, and no reader outside the step sees it.
inline constexpr BufferId kMovedOutputs[] = {BufferId::node_world, BufferId::vertex_position,
                                             BufferId::vertex_normal};

/// Brackets a change of the instance list (Backend::begin_instance_change).
struct InstanceChangeBracket {
    Backend& backend;
    explicit InstanceChangeBracket(Backend& b) : backend(b) { backend.begin_instance_change(); }
    ~InstanceChangeBracket() { backend.end_instance_change(); }
    InstanceChangeBracket(const InstanceChangeBracket&) = delete;
    InstanceChangeBracket& operator=(const InstanceChangeBracket&) = delete;
};

/// Whether half `h` of chain-scope buffer `id` holds values a later step reads, so that it moves
/// with a shifted instance. R and O hold the pose only in the pose half (HMSM_FINAL_HALF of the
/// scene's rounds): every later reader reads that half, and the rounds of passes 3 and 5 write
/// the other before they read it (docs/model.md 3.7, ping-pong halves); a paused instance's
/// rounds skip it and read neither. Every other buffer's halves (the loads: the half the last
/// step wrote) all move.
inline bool half_moves(BufferId id, uint32_t h, uint32_t pose_half) {
    if (id == BufferId::chain_rotation || id == BufferId::chain_origin) return h == pose_half;
    return h < halves_of(id);
}

/// Writes origins and yaws of the instances in `runs` (ranges of indices) from d's instance
/// arrays, every run in one write_ranges per buffer.
inline Status write_origins_and_yaws(Backend& backend, const SceneData& d, std::span<const ElementRange> runs) {
    std::vector<double> values;
    for (BufferId id : {BufferId::instance_origin, BufferId::instance_yaw}) {
        const auto& source = id == BufferId::instance_origin ? d.instance_origin : d.instance_yaw;
        values.clear();
        for (const ElementRange& r : runs)
            for (uint64_t i = r.first; i < r.first + r.count; ++i)
                for (int c = 0; c < 4; ++c) values.push_back(source[i][c]);
        HMSM_TRY(backend.write_ranges(id, runs, values.data(), Scalar::f64));
    }
    return {};
}

/// Appends a move of `count` elements from `src` to `dst`, joined to the move before where both
/// continue it.
inline void append_move(std::vector<ElementMove>& moves, uint64_t src, uint64_t dst, uint64_t count) {
    if (count == 0) return;
    if (!moves.empty() && moves.back().src + moves.back().count == src && moves.back().dst + moves.back().count == dst)
        moves.back().count += count;
    else
        moves.push_back({src, dst, count});
}

/// Appends range [first, first + count), joined to the range before where it continues it.
inline void append_range(std::vector<ElementRange>& ranges, uint64_t first, uint64_t count) {
    if (count == 0) return;
    if (!ranges.empty() && ranges.back().first + ranges.back().count == first) ranges.back().count += count;
    else ranges.push_back({first, count});
}

/// A swap removal of `removed` (ascending, each once, fewer than `count`) from `count`
/// instances: the holes below the new count take, in ascending order, the survivors at or past it.
struct SwapFill {
    std::vector<uint32_t> holes, fillers;
    uint32_t kept = 0;
};
inline SwapFill swap_fill(const std::vector<uint32_t>& removed, uint32_t count) {
    SwapFill fill;
    fill.kept = count - uint32_t(removed.size());
    size_t past = 0;
    for (; past < removed.size() && removed[past] < fill.kept; ++past) fill.holes.push_back(removed[past]);
    for (uint32_t i = fill.kept, r = uint32_t(past); i < count; ++i) {
        if (r < removed.size() && removed[r] == i) ++r;
        else fill.fillers.push_back(i);
    }
    return fill;
}

/// Neighbouring instances [first, end): read, carried and written as one range.
struct IndexRun {
    uint32_t first = 0, end = 0;
};

/// The runs of neighbours in `ascending` (instance indices, ascending, each once).
inline std::vector<IndexRun> index_runs(std::span<const uint32_t> ascending) {
    std::vector<IndexRun> runs;
    for (uint32_t i : ascending) {
        if (!runs.empty() && runs.back().end == i) ++runs.back().end;
        else runs.push_back({i, i + 1});
    }
    return runs;
}

/// index_runs as ranges of indices.
inline std::vector<ElementRange> index_ranges(std::span<const uint32_t> ascending) {
    std::vector<ElementRange> ranges;
    for (uint32_t i : ascending) append_range(ranges, i, 1);
    return ranges;
}

/// `ascending` (moves in ascending order of source and destination) in an order that
/// Backend::move_elements may apply one after another (shift_moves below says why one exists):
/// each run of moves shifting the same way, down in ascending order, up in descending order.
inline std::vector<ElementMove> ordered_shifts(const std::vector<ElementMove>& ascending) {
    std::vector<ElementMove> ordered;
    ordered.reserve(ascending.size());
    for (size_t k = 0; k < ascending.size();) {
        const bool up = ascending[k].dst > ascending[k].src;
        size_t end = k + 1;
        while (end < ascending.size() && (ascending[end].dst > ascending[end].src) == up) ++end;
        if (up) std::reverse_copy(ascending.begin() + std::ptrdiff_t(k), ascending.begin() + std::ptrdiff_t(end),
                                  std::back_inserter(ordered));
        else ordered.insert(ordered.end(), ascending.begin() + std::ptrdiff_t(k), ascending.begin() + std::ptrdiff_t(end));
        k = end;
    }
    return ordered;
}

/// Moves bringing the elements of every instance not listed in `resized` (ascending, each
/// once) from [old[i], old[i + 1]) to [now[i], now[i + 1]), a run of neighbours as one move,
/// in an order that Backend::move_elements may apply one after another: no move writes over
/// the source of a move after it. `old` and `now` are running sums over the `count` instances
/// (read at 0, `count` and each resized instance and the one after it only), equal in each
/// instance that is not resized.
///
/// Why an order exists and which: the moves keep their order in sources and destinations,
/// so a move j writes over the source of a move k only if every move from j to k shifts the
/// same way (all up or all down): the destinations between them lie past D_j's end, beyond
/// S_k's start, so beyond their own sources (and symmetrically going down). Runs of moves that
/// shift the same way are thus independent; one going down runs in ascending order, one going
/// up in descending order. Costs O(resized) lookups.
template <class Offsets>
std::vector<ElementMove> shift_moves(const Offsets& old, const Offsets& now, uint32_t count,
                                     std::span<const uint32_t> resized) {
    std::vector<ElementMove> ascending;
    uint32_t begin = 0;  // first instance of the run that is not resized
    for (size_t k = 0; k <= resized.size(); ++k) {
        const uint32_t end = k < resized.size() ? resized[k] : count;
        if (end > begin && old[begin] != now[begin] && old[end] > old[begin])
            ascending.push_back({old[begin], now[begin], old[end] - old[begin]});
        begin = end + 1;
    }
    return ordered_shifts(ascending);
}

/// shift_moves over running sums held whole (one more entry than instances).
inline std::vector<ElementMove> shift_moves(std::span<const uint64_t> old, std::span<const uint64_t> now,
                                            std::span<const uint32_t> resized) {
    return shift_moves(old, now, uint32_t(old.size() - 1), resized);
}

}  // namespace hmsm::detail
