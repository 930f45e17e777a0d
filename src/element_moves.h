// How a device backend carries out Backend::move_elements (src/backend.h) with bounded scratch:
// moves whose destinations lie apart from every source are copied directly; otherwise the
// moves go through scratch in batches (plan_move_batches): all sources of a batch are gathered
// into scratch, then scattered to their destinations, with at most kMoveScratchBytes in flight.
#pragma once

#include "backend.h"

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <iterator>
#include <map>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace hmsm::detail {

/// The most bytes a device backend stages at a time for a move whose source and destination
/// overlap: a longer move goes through its scratch in chunks of this size.
constexpr uint64_t kMoveScratchBytes = uint64_t(32) << 20;

/// Whether a device backend batches its range transfers (read_ranges, write_ranges,
/// move_elements through plan_move_batches): yes unless the environment sets
/// HMSM_BATCH_TRANSFERS=0, which makes them one copy per range or move (for A/B measurements).
inline bool batch_transfers_enabled() {
    const char* value = std::getenv("HMSM_BATCH_TRANSFERS");
    return !(value && std::string_view(value) == "0");
}

/// Whether a device backend expands Backend::copy_patterns on the device
/// (BackendCapabilities::copies_patterns): yes unless the environment sets
/// HMSM_PATTERN_COPIES=0 (for A/B measurements and tests).
inline bool pattern_copies_enabled() {
    const char* value = std::getenv("HMSM_PATTERN_COPIES");
    return !(value && std::string_view(value) == "0");
}

/// Whether two of `ranges` share an element (a batched write of them could then leave either
/// value). O(n log n).
inline bool ranges_overlap(std::span<const ElementRange> ranges) {
    std::vector<ElementRange> sorted;
    sorted.reserve(ranges.size());
    for (const ElementRange& r : ranges)
        if (r.count > 0) sorted.push_back(r);
    std::sort(sorted.begin(), sorted.end(), [](const ElementRange& a, const ElementRange& b) { return a.first < b.first; });
    for (size_t k = 1; k < sorted.size(); ++k)
        if (sorted[k - 1].first + sorted[k - 1].count > sorted[k].first) return true;
    return false;
}

/// Whether `m` changes something and its source and destination overlap (it must then go
/// through scratch).
inline bool overlaps_itself(const ElementMove& m) {
    return m.src != m.dst && m.count > 0 && (m.src < m.dst ? m.dst - m.src : m.src - m.dst) < m.count;
}

/// Whether every destination of `moves` lies apart from every source (as a swap removal's
/// do): then all of them can be copied at once, without scratch or ordering between them.
inline bool destinations_apart_from_sources(std::span<const ElementMove> moves) {
    uint64_t lowest_src = ~uint64_t(0), highest_dst_end = 0;
    for (const ElementMove& m : moves) {
        if (m.src == m.dst || m.count == 0) continue;
        lowest_src = std::min(lowest_src, m.src);
        highest_dst_end = std::max(highest_dst_end, m.dst + m.count);
    }
    return highest_dst_end <= lowest_src;
}

/// Whether `moves` may be copied all at once, in any order: no destination shares an element
/// with a source or with another destination (a swap removal's moves in each half of a
/// ping-pong buffer, which destinations_apart_from_sources does not see). O(n log n).
inline bool moves_independent(std::span<const ElementMove> moves) {
    std::vector<ElementRange> sources, targets;
    for (const ElementMove& m : moves) {
        if (m.src == m.dst || m.count == 0) continue;
        sources.push_back({m.src, m.count});
        targets.push_back({m.dst, m.count});
    }
    if (ranges_overlap(targets)) return false;
    std::sort(sources.begin(), sources.end(), [](const ElementRange& a, const ElementRange& b) { return a.first < b.first; });
    std::vector<uint64_t> reach(sources.size());  // the furthest end of sources [0, k]
    for (size_t k = 0; k < sources.size(); ++k)
        reach[k] = std::max(k > 0 ? reach[k - 1] : 0, sources[k].first + sources[k].count);
    for (const ElementRange& t : targets) {
        // The sources that begin before the target ends overlap it where one reaches past its start.
        const auto before = std::lower_bound(sources.begin(), sources.end(), t.first + t.count,
                                             [](const ElementRange& r, uint64_t end) { return r.first < end; });
        if (before != sources.begin() && reach[size_t(before - sources.begin()) - 1] > t.first) return false;
    }
    return true;
}

/// Calls `chunk(src, dst, count)` for pieces of `m` of at most `most` elements, in the order
/// that reads every piece of the source before a piece of the destination overwrites it
/// (ascending when the move goes down, descending when it goes up).
template <class Chunk>
Status for_each_chunk(const ElementMove& m, uint64_t most, Chunk&& chunk) {
    const uint64_t pieces = (m.count + most - 1) / most;
    for (uint64_t k = 0; k < pieces; ++k) {
        const uint64_t piece = m.src > m.dst ? k : pieces - 1 - k;
        const uint64_t first = piece * most, count = std::min(most, m.count - first);
        HMSM_TRY(chunk(m.src + first, m.dst + first, count));
    }
    return {};
}

/// Disjoint intervals [first, end) of elements or bytes, for overlap queries. The moves of a
/// level switch or a swap removal add tens of thousands of intervals a call, nearly all in a
/// few ascending or descending sequences (staging, shifts, unstaging): each such sequence is a
/// sorted run, searched in O(log n); an interval that continues no run starts one, and past
/// kMostRuns runs the rest go to a map. A query outside the bounds of everything held is O(1).
class DisjointIntervals {
public:
    /// Whether [first, end) (first < end) shares an element with an interval held.
    bool overlaps(uint64_t first, uint64_t end) const {
        if (end <= lowest_ || first >= highest_) return false;
        for (const Run& run : runs_)
            if (run.overlaps(first, end)) return true;
        return map_overlaps(first, end);
    }
    /// Adds [first, end) (first < end), which overlaps none held.
    void add(uint64_t first, uint64_t end) {
        lowest_ = std::min(lowest_, first);
        highest_ = std::max(highest_, end);
        for (Run& run : runs_)
            if (run.continues(first, end)) {
                run.intervals.push_back({first, end});
                return;
            }
        if (runs_.size() < kMostRuns) {
            runs_.push_back({{{first, end}}, false});
            return;
        }
        map_.emplace(first, end);
    }
    void clear() {
        runs_.clear();
        map_.clear();
        lowest_ = ~uint64_t(0);
        highest_ = 0;
    }

private:
    static constexpr size_t kMostRuns = 8;
    struct Run {
        std::vector<std::pair<uint64_t, uint64_t>> intervals;  // ascending, or descending
        bool descending = false;
        /// Whether [first, end) extends the run in its direction (a run of one takes either).
        bool continues(uint64_t first, uint64_t end) {
            const auto& [back_first, back_end] = intervals.back();
            if (intervals.size() == 1) {
                if (back_end > first && end > back_first) return false;
                descending = end <= back_first;
                return true;
            }
            return descending ? end <= back_first : back_end <= first;
        }
        bool overlaps(uint64_t first, uint64_t end) const {
            // Past either end of the run (a sequence's next interval): O(1).
            const auto& [low, high] = descending ? std::pair(intervals.back().first, intervals.front().second)
                                                 : std::pair(intervals.front().first, intervals.back().second);
            if (end <= low || first >= high) return false;
            // The interval with the largest start below `end` is the only one that can overlap.
            if (!descending) {
                auto after = std::lower_bound(intervals.begin(), intervals.end(), end,
                                              [](const auto& i, uint64_t at) { return i.first < at; });
                return after != intervals.begin() && std::prev(after)->second > first;
            }
            auto below = std::lower_bound(intervals.begin(), intervals.end(), end,
                                          [](const auto& i, uint64_t at) { return i.first >= at; });
            return below != intervals.end() && below->second > first;
        }
    };
    bool map_overlaps(uint64_t first, uint64_t end) const {
        auto after = map_.upper_bound(first);
        if (after != map_.end() && after->first < end) return true;
        return after != map_.begin() && std::prev(after)->second > first;
    }
    std::vector<Run> runs_;
    std::map<uint64_t, uint64_t> map_;  // first -> end, past kMostRuns runs
    uint64_t lowest_ = ~uint64_t(0), highest_ = 0;
};

/// The moves of one move_elements call as batches that each go through scratch at once: every
/// source of a batch is copied into scratch, back to back, then every destination from there.
/// That equals applying the batch's moves one after another exactly when no move reads an
/// element an earlier move of the batch writes and no two of them write the same element; a
/// batch therefore ends before a move that would break either, or overflow the scratch. The
/// moves of shift_moves (instance_moves.h) break neither and make one batch per scratch-full.
struct MoveBatches {
    /// The moves that change something, in order; one longer than the scratch is cut into
    /// pieces in for_each_chunk's order.
    std::vector<ElementMove> pieces;
    /// Batch k is pieces [ends[k - 1], ends[k]) (ends[-1] = 0).
    std::vector<size_t> ends;
    /// Elements of the largest batch: the scratch it needs.
    uint64_t largest = 0;
};

/// Cuts `moves` into batches of at most `scratch_elements` elements (>= 1). O(n log n).
inline MoveBatches plan_move_batches(std::span<const ElementMove> moves, uint64_t scratch_elements) {
    MoveBatches plan;
    DisjointIntervals written;  // destinations of the open batch
    uint64_t in_batch = 0;
    auto close_batch = [&] {
        if (in_batch == 0) return;
        plan.ends.push_back(plan.pieces.size());
        plan.largest = std::max(plan.largest, in_batch);
        in_batch = 0;
        written.clear();
    };
    auto add = [&](uint64_t src, uint64_t dst, uint64_t count) -> Status {
        if (in_batch + count > scratch_elements || written.overlaps(src, src + count) ||
            written.overlaps(dst, dst + count))
            close_batch();
        plan.pieces.push_back({src, dst, count});
        written.add(dst, dst + count);
        in_batch += count;
        return {};
    };
    for (const ElementMove& m : moves) {
        if (m.src == m.dst || m.count == 0) continue;
        (void)for_each_chunk(m, scratch_elements, add);
    }
    close_batch();
    return plan;
}

/// The batches of every buffer of one move_buffers call (plan_move_batches), planned once per
/// distinct list of moves: the carried buffers of a level switch or a swap removal move the
/// same elements (a ping-pong buffer's second half aside), and planning dominates such a call's
/// host time. Every plan takes the scratch of the call's largest element (`element_bytes(id)`),
/// so that one plan serves every buffer. plans[k] is moves[k]'s, valid while `storage` lives.
template <class ElementBytes>
std::vector<const MoveBatches*> plan_buffer_moves(std::span<const BufferMoves> moves, ElementBytes&& element_bytes,
                                                  std::vector<MoveBatches>& storage) {
    uint64_t largest = 1;
    for (const BufferMoves& m : moves) largest = std::max<uint64_t>(largest, element_bytes(m.id));
    const uint64_t scratch_elements = std::max<uint64_t>(1, kMoveScratchBytes / largest);
    storage.clear();
    storage.reserve(moves.size());
    std::vector<const MoveBatches*> plans(moves.size(), nullptr);
    for (size_t k = 0; k < moves.size(); ++k) {
        for (size_t j = 0; j < k && !plans[k]; ++j)
            if (moves[j].moves.size() == moves[k].moves.size() &&
                (moves[j].moves.data() == moves[k].moves.data() ||
                 std::equal(moves[j].moves.begin(), moves[j].moves.end(), moves[k].moves.begin(),
                            [](const ElementMove& a, const ElementMove& b) {
                                return a.src == b.src && a.dst == b.dst && a.count == b.count;
                            })))
                plans[k] = plans[j];
        if (!plans[k]) plans[k] = &storage.emplace_back(plan_move_batches(moves[k].moves, scratch_elements));
    }
    return plans;
}

/// The tables a device backend expands Backend::copy_patterns from: an entry per copy and every
/// pattern's moves once, and per entry the elements its pattern reaches from its src and from
/// its dst (the ranges a backend checks).
struct PatternTables {
    struct Entry {
        uint64_t src = 0, dst = 0;
        uint32_t first_move = 0, move_count = 0;
    };
    std::vector<Entry> entries;
    std::vector<ElementMove> moves;
    std::vector<uint64_t> src_reach, dst_reach;
};

inline Result<PatternTables> pattern_tables(std::span<const MovePattern> patterns, std::span<const PatternCopy> copies) {
    PatternTables t;
    std::vector<uint32_t> first_move;
    std::vector<uint64_t> src_reach, dst_reach;
    for (const MovePattern& p : patterns) {
        first_move.push_back(uint32_t(t.moves.size()));
        uint64_t src = 0, dst = 0;
        for (const ElementMove& m : p.moves) {
            src = std::max(src, m.src + m.count);
            dst = std::max(dst, m.dst + m.count);
            t.moves.push_back(m);
        }
        src_reach.push_back(src);
        dst_reach.push_back(dst);
    }
    for (const PatternCopy& c : copies) {
        if (c.pattern >= patterns.size())
            return Status{ErrorCode::internal, "copy_patterns: pattern " + std::to_string(c.pattern) + " of " +
                                                   std::to_string(patterns.size())};
        t.entries.push_back({c.src, c.dst, first_move[c.pattern], uint32_t(patterns[c.pattern].moves.size())});
        t.src_reach.push_back(src_reach[c.pattern]);
        t.dst_reach.push_back(dst_reach[c.pattern]);
    }
    return t;
}

/// Checks every entry of `t` against `check_range(first, count)` in each buffer of `ids` (both
/// halves of a ping-pong buffer, the second from element `capacity` on).
template <class CheckRange>
Status check_pattern_ranges(const PatternTables& t, std::span<const BufferId> ids, uint64_t capacity,
                            CheckRange&& check_range) {
    for (BufferId id : ids) {
        const uint64_t half = buffer_info(id).scope == Scope::chain_halves ? capacity : 0;
        for (size_t k = 0; k < t.entries.size(); ++k) {
            HMSM_TRY(check_range(id, t.entries[k].src + half, t.src_reach[k]));
            HMSM_TRY(check_range(id, t.entries[k].dst + half, t.dst_reach[k]));
        }
    }
    return {};
}

}  // namespace hmsm::detail
