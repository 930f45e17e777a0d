// Batched launches (CUDA): one kernel launch runs a run of dispatches over different instance
// groups (step_program.h dispatch_batches). Entry e of the launch is one dispatch: its constants
// and a range of the grid's blocks, [block_begin[e], block_begin[e + 1]). Each block finds its
// entry by a binary search over these prefixes, loads that entry's constants and runs the
// dispatch's per-element code as block `block` of a grid of the entry's own `blocks` blocks, so
// every thread computes exactly what it computes in the dispatch's own launch. Host and device:
// the kernels, the host emulation and the launch planner share these functions.
#pragma once

#include "gpu_layout.h"
#include "host_device.h"

#include <cstdint>

namespace hmsm::detail {

/// What a batched kernel takes besides the buffer pointers, by value (a captured graph node is
/// re-parameterized with a new wind slot like a single dispatch's).
struct BatchLaunch {
    const gpu::PassConstants* constants = nullptr;  // entry e's dispatch constants
    const uint32_t* block_begin = nullptr;  // entries + 1 values, ascending: entry e's first block;
                                            // block_begin[entries] is the grid
    uint32_t entries = 0;
    uint32_t wind_slot = 0;       // the step's wind-table slot
    uint32_t sets_wind_slot = 0;  // 1: wind_slot replaces every entry's (the run reads the slot)
    uint32_t reserved = 0;
};

/// Block `block` of a batched launch as its entry sees it: the entry, the block within the
/// entry's grid, and that grid's size (the stride of the entry's grid-stride loop).
struct BatchBlock {
    uint32_t entry;
    uint32_t block;
    uint32_t blocks;
};

/// The entry whose block range holds `block` (< block_begin[entries]): the last e with
/// block_begin[e] <= block. Entries of no blocks are passed over.
HMSM_HOST_DEVICE uint32_t batch_entry(const uint32_t* block_begin, uint32_t entries, uint32_t block) {
    uint32_t low = 0, high = entries;  // block_begin[low] <= block < block_begin[high]
    while (high - low > 1) {
        const uint32_t middle = low + (high - low) / 2;
        if (block_begin[middle] <= block) low = middle;
        else high = middle;
    }
    return low;
}

HMSM_HOST_DEVICE BatchBlock batch_block(const uint32_t* block_begin, uint32_t entries, uint32_t block) {
    const uint32_t entry = batch_entry(block_begin, entries, block);
    return {entry, block - block_begin[entry], block_begin[entry + 1] - block_begin[entry]};
}

/// The constants entry `entry` runs with: its dispatch's, with the step's wind slot where the run
/// reads it (launch_dispatch.cpp step_constants does the same for a single dispatch).
HMSM_HOST_DEVICE gpu::PassConstants batch_constants(const BatchLaunch& batch, uint32_t entry) {
    gpu::PassConstants pc = batch.constants[entry];
    if (batch.sets_wind_slot != 0) pc.wind_slot = batch.wind_slot;
    return pc;
}

/// Blocks of `threads` threads for `items` work items, at most max_blocks (a capped grid's
/// threads stride over the rest).
HMSM_HOST_DEVICE uint32_t capped_blocks(uint64_t items, uint32_t threads, uint32_t max_blocks) {
    const uint64_t blocks = (items + threads - 1) / threads;
    return blocks < max_blocks ? uint32_t(blocks) : max_blocks;
}

/// Most blocks of a JUMP_ROUNDS_IN_DISPATCH launch (one per instance; blocks stride beyond).
#define HMSM_MAX_ROUNDS_BLOCKS (1u << 24)

/// Work items of a dispatch, which its threads take one by one: a vertex group of a packed
/// contour (gpu_layout.h HMSM_PACKED_CONTOUR_INSTANCES, at most 2^32 - 1 counted for the grid),
/// an instance of in-dispatch rounds or of a sweep (a block each), else an element.
HMSM_HOST_DEVICE uint64_t dispatch_items(const gpu::PassConstants& pc) {
    if (pc.kind == HMSM_DISPATCH_CONTOUR_PACKED) {
        const uint64_t items = gpu::packed_contour_threads(pc);
        return items < 0xffffffffull ? items : 0xffffffffull;
    }
    if (pc.kind == HMSM_DISPATCH_JUMP_ROUNDS_IN_DISPATCH || pc.kind == HMSM_DISPATCH_INSTANCE_SWEEP)
        return pc.element_count / pc.model_chain_count;
    return pc.element_count;
}

/// Blocks of a dispatch's launch of `threads`-thread blocks, as its own launch takes them
/// (pass_math.cuh launch_blocks, launch_blocks_per_instance; contour.cu): `max_blocks`
/// (HMSM_CUDA_MAX_BLOCKS) caps the per-element grids, HMSM_MAX_ROUNDS_BLOCKS the rounds'.
HMSM_HOST_DEVICE uint32_t dispatch_blocks(const gpu::PassConstants& pc, uint32_t threads, uint32_t max_blocks) {
    if (pc.element_count == 0) return 0;
    if (pc.kind == HMSM_DISPATCH_JUMP_ROUNDS_IN_DISPATCH || pc.kind == HMSM_DISPATCH_INSTANCE_SWEEP)
        return capped_blocks(dispatch_items(pc), 1, HMSM_MAX_ROUNDS_BLOCKS);
    return capped_blocks(dispatch_items(pc), threads, max_blocks);
}

}  // namespace hmsm::detail
