// Copies between many ranges of one device buffer and a packed scratch buffer in one launch:
// the batched transfers of the CUDA backend (Backend::read_ranges, write_ranges and
// move_elements, src/cuda/device_buffers.cpp). Buffers are counted in 32-bit words (every
// device element is a whole number of them).
#pragma once

#include "../../src/common/host_device.h"

#include <cuda_runtime_api.h>

#include <cstdint>
#ifndef __CUDACC__  // the host side (C++20); kernels compile as C++17
#include "../../src/element_moves.h"

#include <span>
#include <vector>
#endif

namespace hmsm::detail::cuda {

/// One range: words [packed, packed + words) of scratch are words [source, source + words) of
/// the buffer when gathered, and go to [target, target + words) when scattered. `packed` runs
/// over the ranges back to back, ascending.
struct WordRange {
    uint64_t packed = 0, words = 0, source = 0, target = 0;
};

enum class RangeCopy : uint32_t { gather, scatter };

/// Word `t` of the packed scratch (t < the ranges' total words): gather copies it from the
/// buffer into scratch, scatter from scratch into the buffer. Finds its range by bisection.
HMSM_HOST_DEVICE void copy_range_word(uint32_t* buffer, uint32_t* packed, const WordRange* ranges,
                                      uint32_t range_count, uint64_t t, RangeCopy direction) {
    uint32_t low = 0, high = range_count;  // the range holding t: the last one whose packed <= t
    while (high - low > 1) {
        const uint32_t middle = low + (high - low) / 2;
        if (ranges[middle].packed <= t) low = middle;
        else high = middle;
    }
    const WordRange& r = ranges[low];
    const uint64_t offset = t - r.packed;
    if (direction == RangeCopy::gather) packed[t] = buffer[r.source + offset];
    else buffer[r.target + offset] = packed[t];
}

/// One copy of Backend::copy_patterns (src/backend.h PatternCopy) as the device reads it: its
/// source and destination element and its pattern's moves, [first_move, first_move +
/// move_count) of the call's PatternMoveEntry table.
struct PatternCopyEntry {
    uint64_t src = 0, dst = 0;
    uint32_t first_move = 0, move_count = 0;
};
/// One move of a pattern, in elements (ElementMove's fields).
struct PatternMoveEntry {
    uint64_t src = 0, dst = 0, count = 0;
};
#ifndef __CUDACC__
static_assert(sizeof(PatternCopyEntry) == sizeof(PatternTables::Entry) &&
                  sizeof(PatternMoveEntry) == sizeof(ElementMove),
              "the host's pattern tables are copied to the device as they are");
#endif

/// The words of copy `entry` in `buffer` (elements of `words_per_element` words), taken by
/// threads `thread`, `thread + threads`, ... of each of its moves in turn.
HMSM_HOST_DEVICE void copy_pattern_words(uint32_t* buffer, uint32_t words_per_element, const PatternCopyEntry& entry,
                                         const PatternMoveEntry* moves, uint32_t thread, uint32_t threads) {
    for (uint32_t k = 0; k < entry.move_count; ++k) {
        const PatternMoveEntry& m = moves[entry.first_move + k];
        const uint64_t src = (entry.src + m.src) * words_per_element, dst = (entry.dst + m.dst) * words_per_element;
        const uint64_t words = m.count * words_per_element;
        for (uint64_t w = thread; w < words; w += threads) buffer[dst + w] = buffer[src + w];
    }
}

#ifndef __CUDACC__
/// Appends the ranges of `pieces` (elements of `words_per_element` words; src is gathered from,
/// dst scattered to) to `out`, packed after what `out` holds; returns the words they span.
inline uint64_t append_word_ranges(std::vector<WordRange>& out, std::span<const ElementMove> pieces,
                                   uint64_t words_per_element, uint64_t packed_at = 0) {
    uint64_t total = 0;
    for (const ElementMove& m : pieces) {
        if (m.count == 0) continue;
        const uint64_t words = m.count * words_per_element;
        out.push_back({packed_at + total, words, m.src * words_per_element, m.dst * words_per_element});
        total += words;
    }
    return total;
}
#endif

/// Enqueues one launch copying every word of `ranges` (device memory, range_count entries, `total`
/// words) between `buffer` and `packed`.
cudaError_t launch_copy_ranges(uint32_t* buffer, uint32_t* packed, const WordRange* ranges, uint32_t range_count,
                               uint64_t total, RangeCopy direction, cudaStream_t stream);
/// The same on the host, word by word (ranges in host memory).
void emulate_copy_ranges(uint32_t* buffer, uint32_t* packed, const WordRange* ranges, uint32_t range_count,
                         uint64_t total, RangeCopy direction);

/// Enqueues one launch copying every entry of `entries` (device memory, with their `moves`) in
/// each of `halves` halves of `buffer`, the second `half_words` words after the first: a block
/// per entry and half. The entries' destinations are apart from every source and destination.
cudaError_t launch_copy_patterns(uint32_t* buffer, uint32_t words_per_element, uint64_t half_words, uint32_t halves,
                                 const PatternCopyEntry* entries, uint32_t entry_count, const PatternMoveEntry* moves,
                                 cudaStream_t stream);
/// The same on the host (tables in host memory).
void emulate_copy_patterns(uint32_t* buffer, uint32_t words_per_element, uint64_t half_words, uint32_t halves,
                           const PatternCopyEntry* entries, uint32_t entry_count, const PatternMoveEntry* moves);

}  // namespace hmsm::detail::cuda
