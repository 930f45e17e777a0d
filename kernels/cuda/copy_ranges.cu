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

}  // namespace hmsm::detail::cuda
