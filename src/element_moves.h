// How a device backend carries out Backend::move_elements (src/backend.h) with bounded scratch:
// moves whose destinations lie apart from every source are copied directly, a move that
// overlaps itself goes through scratch in chunks of at most kMoveScratchBytes.
#pragma once

#include "backend.h"

#include <algorithm>
#include <cstdint>
#include <span>

namespace hmsm::detail {

/// The most bytes a device backend stages at a time for a move whose source and destination
/// overlap: a longer move goes through its scratch in chunks of this size.
constexpr uint64_t kMoveScratchBytes = uint64_t(32) << 20;

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

}  // namespace hmsm::detail
