// One step of a program as an instantiated CUDA graph, replayed once per step.
//
// The program is captured once from the stream (its launches in order, launch_plan.h: each run
// of dispatches over different groups one batched launch; ordering replaces barriers; a launch
// that does not depend on the one before it runs beside it, step_graph.cpp). Between replays
// only the step's wind-table slot (gpu_layout.h) changes: it lives in the constants
// (pc.wind_slot) of the dispatches that read it (backend.h reads_wind_slot: wind_force, the top
// poses and the walk ahead), or for a batch in its BatchLaunch, which overrides its entries'
// slot, so before each replay every such kernel node gets new parameters through
// cudaGraphExecKernelNodeSetParams. That is possible generically because every pass kernel
// takes (BufferPointers, PassConstants or BatchLaunch) by value (launchers.h). Launches already enqueued keep
// the parameters they were launched with, so steps can be enqueued back to back.
#pragma once

#include "../backend.h"
#include "../../kernels/cuda/launchers.h"
#include "launch_plan.h"

#include <span>
#include <vector>

namespace hmsm::detail::cuda {

/// Whether two dispatches are the same launch: pass and constants, bit for bit.
bool same_dispatch(const Dispatch& a, const Dispatch& b);
/// Whether two programs are the same launches in the same order.
bool same_dispatches(std::span<const Dispatch> a, std::span<const Dispatch> b);
/// Whether programs `a` and `b`, named `a_id` and `b_id` (Backend::run's program_id; 0: none),
/// are the same: by their ids where both have one (an id names one program, and a program given
/// a new id is taken as new: a forest's has tens of thousands of dispatches), else by comparing.
bool same_program(std::span<const Dispatch> a, uint64_t a_id, std::span<const Dispatch> b, uint64_t b_id);

class StepGraph {
public:
    StepGraph() = default;
    ~StepGraph();
    StepGraph(const StepGraph&) = delete;
    StepGraph& operator=(const StepGraph&) = delete;

    /// True when the captured graph runs exactly `program` over `buffers`: the program it was
    /// captured from is `program` by same_program.
    bool matches(std::span<const Dispatch> program, const BufferPointers& buffers, uint64_t program_id = 0) const;
    /// Captures `program` from `stream` and instantiates it (replacing any earlier graph), its
    /// runs batched unless `batch_runs` is false (launch_plan.h; the batches' table is uploaded
    /// first, into the slot of the table the graph before the last one read).
    Status capture(std::span<const Dispatch> program, const BufferPointers& buffers, bool batch_runs,
                   cudaStream_t stream, uint64_t program_id = 0);
    /// Enqueues one step reading wind-table slot `wind_slot` on `stream`.
    Status replay(uint32_t wind_slot, cudaStream_t stream);

private:
    /// A node whose kernel reads the wind slot: a single dispatch's (its constants) or a
    /// batch's (its BatchLaunch, which sets the slot of every entry).
    struct WindNode {
        cudaGraphNode_t node;
        cudaKernelNodeParams launch;  // function and grid of the captured node
        bool batched;
        gpu::PassConstants constants;
        BatchLaunch batch;
    };
    void release();

    std::vector<Dispatch> program_;
    uint64_t program_id_ = 0;  // the id program_ was captured with (0: none)
    LaunchPlan plan_;
    LaunchTable table_;  // the batches' table, kept across captures (regrown where needed)
    BufferPointers buffers_;
    cudaGraph_t graph_ = nullptr;
    cudaGraphExec_t exec_ = nullptr;
    std::vector<WindNode> wind_nodes_;
};

}  // namespace hmsm::detail::cuda
