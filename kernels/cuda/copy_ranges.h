// Copies between many ranges of one device buffer and a packed scratch buffer in one launch:
// the batched transfers of the CUDA backend (Backend::read_ranges, write_ranges and
// move_elements, src/cuda/device_buffers.cpp). Buffers are counted in 32-bit words (every
// device element is a whole number of them).
#pragma once

#include "../../src/common/host_device.h"

#include <cuda_runtime_api.h>

#include <cstdint>
#ifndef __CUDACC__  // the host side (C++20); kernels compile as C++17
#include "../../src/backend.h"

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

}  // namespace hmsm::detail::cuda
