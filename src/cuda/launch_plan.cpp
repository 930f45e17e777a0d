#include "launch_plan.h"

#include "cuda_error.h"
#include "launch_dispatch.h"
#include "../step_program.h"

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <string_view>

namespace hmsm::detail::cuda {

bool batch_runs_enabled() {
    const char* value = std::getenv("HMSM_CUDA_BATCH_RUNS");
    return !(value && std::string_view(value) == "0");
}

uint32_t dispatch_threads(const gpu::PassConstants& pc) {
    if (pc.kind == HMSM_DISPATCH_JUMP_ROUNDS_IN_DISPATCH) return gpu::rounds_workgroup_size(pc.model_chain_count);
    if (pc.kind == HMSM_DISPATCH_CONTOUR_SEPARATE) return 256;  // contour.cu kSeparateThreads
    if (pc.kind == HMSM_DISPATCH_INSTANCE_SWEEP)
        return gpu::sweep_workgroup_size(pc.element_count / pc.model_chain_count, pc.model_chain_count);
    return HMSM_WORKGROUP_SIZE;
}

BatchLaunch LaunchPlan::batch(const PlannedLaunch& launch, const gpu::PassConstants* constants_base,
                              const uint32_t* block_begin_base, uint32_t wind_slot) const {
    BatchLaunch batch;
    batch.constants = constants_base + launch.entry_begin;
    batch.block_begin = block_begin_base + launch.prefix_begin;
    batch.entries = launch.entries;
    batch.wind_slot = wind_slot;
    batch.sets_wind_slot = launch.reads_wind_slot ? 1u : 0u;
    return batch;
}

namespace {

/// The most blocks of one grid (gridDim.x).
constexpr uint64_t kMaxGridBlocks = 0x7fffffffu;

PlannedLaunch single_launch(std::span<const Dispatch> program, const Dispatch& d) {
    PlannedLaunch launch;
    launch.pass = d.pass;
    launch.dispatch = uint32_t(&d - program.data());
    launch.shape.kind = d.constants.kind;
    launch.reads_wind_slot = reads_wind_slot(d);
    launch.reads = dispatch_reads(d);
    launch.writes = dispatch_writes(d);
    return launch;
}

/// Builds the batches of `entries` (dispatches of one run, of one block size) into `plan`.
class BatchBuilder {
public:
    BatchBuilder(LaunchPlan& plan, uint32_t threads, uint32_t max_blocks)
        : plan_(plan), threads_(threads), max_blocks_(max_blocks) {}

    void add(const Dispatch& d) {
        const uint32_t blocks = dispatch_blocks(d.constants, threads_, max_blocks_);
        if (open_ && uint64_t(plan_.block_begin.back()) + blocks > kMaxGridBlocks) close();
        if (!open_) {
            launch_ = PlannedLaunch{};
            launch_.pass = d.pass;
            launch_.entry_begin = uint32_t(plan_.constants.size());
            launch_.prefix_begin = uint32_t(plan_.block_begin.size());
            launch_.shape.kind = d.constants.kind;
            launch_.shape.threads = threads_;
            launch_.reads_wind_slot = reads_wind_slot(d);
            plan_.block_begin.push_back(0);
            open_ = true;
        }
        plan_.constants.push_back(d.constants);
        plan_.block_begin.push_back(plan_.block_begin.back() + blocks);
        ++launch_.entries;
        launch_.shape.may_pause = launch_.shape.may_pause || d.constants.params.w != 0.0f;
        launch_.reads |= dispatch_reads(d);
        launch_.writes |= dispatch_writes(d);
    }

    void close() {
        if (!open_) return;
        launch_.shape.blocks = plan_.block_begin.back();
        plan_.launches.push_back(launch_);
        open_ = false;
    }

private:
    LaunchPlan& plan_;
    uint32_t threads_, max_blocks_;
    PlannedLaunch launch_;
    bool open_ = false;
};

}  // namespace

LaunchPlan plan_launches(std::span<const Dispatch> program, bool batch_runs, uint32_t max_blocks) {
    LaunchPlan plan;
    plan_launches(program, batch_runs, max_blocks, plan);
    return plan;
}

void plan_launches(std::span<const Dispatch> program, bool batch_runs, uint32_t max_blocks, LaunchPlan& plan) {
    plan.launches.clear();
    plan.constants.clear();
    plan.block_begin.clear();
    const std::vector<std::span<const Dispatch>> runs = dispatch_batches(program);
    if (batch_runs) {  // at most every dispatch an entry, and a prefix more per launch
        plan.constants.reserve(program.size());
        plan.block_begin.reserve(program.size() + 2 * runs.size());
    }
    std::vector<const Dispatch*> entries;
    for (const std::span<const Dispatch> run : runs) {
        entries.clear();
        for (const Dispatch& d : run)
            if (d.constants.element_count > 0) entries.push_back(&d);
        if (!batch_runs || entries.size() < 2) {
            for (const Dispatch& d : run) plan.launches.push_back(single_launch(program, d));
            continue;
        }
        // One launch per block size (in-dispatch rounds of models of different sizes), each
        // keeping the run's order; a size of one entry takes that dispatch's own launch.
        auto threads_of = [](const Dispatch* d) { return dispatch_threads(d->constants); };
        const bool one_size = std::all_of(entries.begin(), entries.end(),
                                          [&](const Dispatch* d) { return threads_of(d) == threads_of(entries[0]); });
        if (!one_size)
            std::stable_sort(entries.begin(), entries.end(),
                             [&](const Dispatch* a, const Dispatch* b) { return threads_of(a) < threads_of(b); });
        for (size_t first = 0; first < entries.size();) {
            size_t end = first + 1;
            while (end < entries.size() && threads_of(entries[end]) == threads_of(entries[first])) ++end;
            if (end - first == 1) {
                plan.launches.push_back(single_launch(program, *entries[first]));
            } else {
                BatchBuilder batch(plan, threads_of(entries[first]), max_blocks);
                for (size_t i = first; i < end; ++i) batch.add(*entries[i]);
                batch.close();
            }
            first = end;
        }
    }
}

cudaError_t enqueue_launch(const LaunchPlan& plan, const PlannedLaunch& launch, std::span<const Dispatch> program,
                           const LaunchTable& table, const BufferPointers& buffers, uint32_t wind_slot,
                           cudaStream_t stream) {
    if (launch.entries == 0) return launch_dispatch(program[launch.dispatch], buffers, wind_slot, stream);
    return launch_batch(launch.pass, buffers, plan.batch(launch, table.constants(), table.block_begin(), wind_slot),
                        launch.shape, stream);
}

void emulate_launch(const LaunchPlan& plan, const PlannedLaunch& launch, std::span<const Dispatch> program,
                    const BufferPointers& host_buffers, uint32_t wind_slot) {
    if (launch.entries == 0) return emulate_dispatch(program[launch.dispatch], host_buffers, wind_slot);
    emulate_batch(launch.pass, host_buffers,
                  plan.batch(launch, plan.constants.data(), plan.block_begin.data(), wind_slot), launch.shape);
}

LaunchTable::~LaunchTable() {
    for (Slot& slot : slots_) release(slot);
}

void LaunchTable::release(Slot& slot) {
    if (slot.constants) (void)cudaFree(slot.constants);
    if (slot.block_begin) (void)cudaFree(slot.block_begin);
    if (slot.staging) (void)cudaFreeHost(slot.staging);
    if (slot.used) (void)cudaEventDestroy(slot.used);
    slot = {};
}

Status LaunchTable::upload(const LaunchPlan& plan, cudaStream_t stream) {
    if (plan.constants.empty()) return {};
    Slot& current = slots_[current_];
    if (current.used) {
        // Every launch that reads the current slot is enqueued before this point.
        CUDA_TRY(cudaEventRecord(current.used, stream));
        current.marked = true;
    }
    const size_t next = current.constants ? 1 - current_ : current_;
    Slot& slot = slots_[next];
    // The launches that read this slot before the previous upload, and its copies.
    if (slot.marked) CUDA_TRY(cudaEventSynchronize(slot.used));
    slot.marked = false;
    if (plan.constants.size() > slot.constants_capacity || plan.block_begin.size() > slot.block_begin_capacity) {
        release(slot);
        CUDA_TRY(cudaMalloc(reinterpret_cast<void**>(&slot.constants), plan.constants.size() * sizeof(gpu::PassConstants)));
        slot.constants_capacity = plan.constants.size();
        CUDA_TRY(cudaMalloc(reinterpret_cast<void**>(&slot.block_begin), plan.block_begin.size() * sizeof(uint32_t)));
        slot.block_begin_capacity = plan.block_begin.size();
        CUDA_TRY(cudaMallocHost(&slot.staging, slot.constants_capacity * sizeof(gpu::PassConstants) +
                                                   slot.block_begin_capacity * sizeof(uint32_t)));
        CUDA_TRY(cudaEventCreateWithFlags(&slot.used, cudaEventDisableTiming));
    }
    auto* staged_constants = static_cast<unsigned char*>(slot.staging);
    unsigned char* staged_block_begin = staged_constants + slot.constants_capacity * sizeof(gpu::PassConstants);
    const size_t constants_bytes = plan.constants.size() * sizeof(gpu::PassConstants);
    const size_t block_begin_bytes = plan.block_begin.size() * sizeof(uint32_t);
    std::memcpy(staged_constants, plan.constants.data(), constants_bytes);
    std::memcpy(staged_block_begin, plan.block_begin.data(), block_begin_bytes);
    CUDA_TRY(cudaMemcpyAsync(slot.constants, staged_constants, constants_bytes, cudaMemcpyHostToDevice, stream));
    CUDA_TRY(cudaMemcpyAsync(slot.block_begin, staged_block_begin, block_begin_bytes, cudaMemcpyHostToDevice, stream));
    current_ = next;
    return {};
}

}  // namespace hmsm::detail::cuda
