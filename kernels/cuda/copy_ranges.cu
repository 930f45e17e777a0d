// The range copies of copy_ranges.h: one thread per word of the packed scratch, a grid-stride
// loop beyond the grid.
#include "copy_ranges.h"

#include <algorithm>

namespace hmsm::detail::cuda {

static constexpr uint32_t kCopyThreads = 256;
static constexpr uint64_t kMostCopyBlocks = 8192;

// Static, like the pass kernels (pass_math.cuh): its launch stub stays local to the library.
static __global__ void __launch_bounds__(kCopyThreads)
    copy_ranges_kernel(uint32_t* buffer, uint32_t* packed, const WordRange* ranges, uint32_t range_count,
                       uint64_t total, RangeCopy direction) {
    for (uint64_t t = uint64_t(blockIdx.x) * blockDim.x + threadIdx.x; t < total; t += uint64_t(gridDim.x) * blockDim.x)
        copy_range_word(buffer, packed, ranges, range_count, t, direction);
}

cudaError_t launch_copy_ranges(uint32_t* buffer, uint32_t* packed, const WordRange* ranges, uint32_t range_count,
                               uint64_t total, RangeCopy direction, cudaStream_t stream) {
    if (total == 0 || range_count == 0) return cudaSuccess;
    const uint64_t blocks = std::min<uint64_t>((total + kCopyThreads - 1) / kCopyThreads, kMostCopyBlocks);
    copy_ranges_kernel<<<unsigned(blocks), kCopyThreads, 0, stream>>>(buffer, packed, ranges, range_count, total,
                                                                       direction);
    return cudaGetLastError();
}

void emulate_copy_ranges(uint32_t* buffer, uint32_t* packed, const WordRange* ranges, uint32_t range_count,
                         uint64_t total, RangeCopy direction) {
    if (range_count == 0) return;
    for (uint64_t t = 0; t < total; ++t) copy_range_word(buffer, packed, ranges, range_count, t, direction);
}

static __global__ void __launch_bounds__(kCopyThreads)
    copy_patterns_kernel(uint32_t* buffer, uint32_t words_per_element, uint64_t half_words,
                         const PatternCopyEntry* entries, uint32_t entry_count, const PatternMoveEntry* moves) {
    uint32_t* half = buffer + blockIdx.y * half_words;
    for (uint32_t e = blockIdx.x; e < entry_count; e += gridDim.x)
        copy_pattern_words(half, words_per_element, entries[e], moves, threadIdx.x, blockDim.x);
}

cudaError_t launch_copy_patterns(uint32_t* buffer, uint32_t words_per_element, uint64_t half_words, uint32_t halves,
                                 const PatternCopyEntry* entries, uint32_t entry_count, const PatternMoveEntry* moves,
                                 cudaStream_t stream) {
    if (entry_count == 0 || halves == 0) return cudaSuccess;
    const dim3 grid(unsigned(std::min<uint64_t>(entry_count, kMostCopyBlocks)), halves);
    copy_patterns_kernel<<<grid, kCopyThreads, 0, stream>>>(buffer, words_per_element, half_words, entries,
                                                            entry_count, moves);
    return cudaGetLastError();
}

void emulate_copy_patterns(uint32_t* buffer, uint32_t words_per_element, uint64_t half_words, uint32_t halves,
                           const PatternCopyEntry* entries, uint32_t entry_count, const PatternMoveEntry* moves) {
    for (uint32_t h = 0; h < halves; ++h)
        for (uint32_t e = 0; e < entry_count; ++e)
            copy_pattern_words(buffer + h * half_words, words_per_element, entries[e], moves, 0, 1);
}

}  // namespace hmsm::detail::cuda
