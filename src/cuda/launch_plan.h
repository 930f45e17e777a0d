// The launches of a step program on CUDA. A run of consecutive dispatches over different groups
// (step_program.h dispatch_batches) is one batched launch (src/common/batch_index.h), so a forest
// of thousands of groups takes about as many launches per step as one tree; a run of one
// dispatch keeps that dispatch's own launch. HMSM_CUDA_BATCH_RUNS=0 in the environment plans one
// launch per dispatch (read when a backend is created, for side-by-side measurements).
//
// The plan is host data (a table of the batched entries' constants and their block prefixes);
// LaunchTable holds its device copy, uploaded when the program changes and kept for as many
// steps as the program runs.
#pragma once

#include "../backend.h"
#include "../../kernels/cuda/launchers.h"

#include <array>
#include <span>
#include <vector>

namespace hmsm::detail::cuda {

/// Whether runs are batched: false where HMSM_CUDA_BATCH_RUNS=0 (read at each call).
bool batch_runs_enabled();

/// One launch of a step: a single dispatch (entries == 0: program[dispatch]) or a batch of
/// entries [entry_begin, entry_begin + entries) of the plan's table, whose block prefixes are
/// block_begin[prefix_begin, prefix_begin + entries].
struct PlannedLaunch {
    Pass pass = Pass::wind_force;
    uint32_t dispatch = 0;
    uint32_t entry_begin = 0, entries = 0, prefix_begin = 0;
    BatchShape shape;
    bool reads_wind_slot = false;
    uint32_t reads = 0, writes = 0;  // buffers read and written (bit = BufferId), over every entry
};

struct LaunchPlan {
    std::vector<PlannedLaunch> launches;
    std::vector<gpu::PassConstants> constants;  // the batched entries, launch after launch
    std::vector<uint32_t> block_begin;          // each batch's entries + 1 block prefixes

    /// A batched launch's kernel parameters over host or device copies of the table.
    BatchLaunch batch(const PlannedLaunch& launch, const gpu::PassConstants* constants_base,
                      const uint32_t* block_begin_base, uint32_t wind_slot) const;
};

/// The threads of a block of `pc`'s launch: rounds_workgroup_size for in-dispatch rounds, 256 for
/// the separate-layout contour, else HMSM_WORKGROUP_SIZE (the launchers' own sizes).
uint32_t dispatch_threads(const gpu::PassConstants& pc);

/// The launches of `program`: each run of dispatch_batches of more than one dispatch batched
/// (unless `batch_runs` is false), its entries' grids capped at `max_blocks` blocks (per-element
/// forms; HMSM_CUDA_MAX_BLOCKS). A run of in-dispatch rounds is split by block size: one launch
/// per rounds_workgroup_size among its entries, so every block has its entry's own size. Empty
/// dispatches take no entry; a batch whose grid would pass 2^31 - 1 blocks is split.
LaunchPlan plan_launches(std::span<const Dispatch> program, bool batch_runs, uint32_t max_blocks);
/// The same into `into`, reusing its vectors' memory.
void plan_launches(std::span<const Dispatch> program, bool batch_runs, uint32_t max_blocks, LaunchPlan& into);

/// Enqueues `launch` of `plan` (of `program`) on `stream`: a single dispatch through
/// launch_dispatch, a batch through its pass's launch_batch_NAME over `table`'s device copy.
class LaunchTable;
cudaError_t enqueue_launch(const LaunchPlan& plan, const PlannedLaunch& launch, std::span<const Dispatch> program,
                           const LaunchTable& table, const BufferPointers& buffers, uint32_t wind_slot,
                           cudaStream_t stream);

/// Runs `launch` on the host (tests): the same, through emulate_dispatch and emulate_batch_NAME
/// over the plan's host table.
void emulate_launch(const LaunchPlan& plan, const PlannedLaunch& launch, std::span<const Dispatch> program,
                    const BufferPointers& host_buffers, uint32_t wind_slot);

/// Device copy of a plan's table, in two slots: an upload fills the slot the previous upload
/// did not, from pinned host memory, so it waits neither for the launches still reading the
/// current table nor for the copy itself (a copy from pageable memory would wait for the whole
/// stream). It waits only where the slot it fills is still read by launches enqueued before the
/// previous upload (an event recorded then marks them). Freed with the object (its owner makes
/// sure no enqueued launch still reads it).
class LaunchTable {
public:
    LaunchTable() = default;
    ~LaunchTable();
    LaunchTable(const LaunchTable&) = delete;
    LaunchTable& operator=(const LaunchTable&) = delete;

    /// Copies the table of `plan` to the device on `stream` (growing the allocation where
    /// needed); launches enqueued on `stream` afterwards read it.
    Status upload(const LaunchPlan& plan, cudaStream_t stream);
    const gpu::PassConstants* constants() const { return slots_[current_].constants; }
    const uint32_t* block_begin() const { return slots_[current_].block_begin; }

private:
    struct Slot {
        gpu::PassConstants* constants = nullptr;  // device
        uint32_t* block_begin = nullptr;          // device
        void* staging = nullptr;                  // pinned host: constants, then block_begin
        size_t constants_capacity = 0, block_begin_capacity = 0;
        cudaEvent_t used = nullptr;  // recorded after the last launch that reads this slot
        bool marked = false;         // `used` was recorded
    };
    static void release(Slot& slot);
    std::array<Slot, 2> slots_;
    size_t current_ = 0;
};

}  // namespace hmsm::detail::cuda
