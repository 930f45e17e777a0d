// The CUDA backend: device buffers, one stream (its own, or one an engine hands in through
// include/hmsm/cuda.h), the step program replayed as a CUDA graph, and per-pass device times
// from CUDA events when profiling. Every copy and launch goes on that stream in call order;
// the host waits for it only in run() (unless enqueuing), reads, moves and uploads.
#pragma once

#include "../backend.h"
#include "../step_program.h"
#include "device_buffers.h"
#include "launch_plan.h"
#include "step_graph.h"

#include <array>
#include <string>
#include <vector>

namespace hmsm::detail::cuda {

class CudaBackend final : public Backend {
public:
    /// no_device when the runtime sees no CUDA device (any cudaGetDeviceCount error counts).
    static Result<std::unique_ptr<Backend>> create();
    ~CudaBackend() override;

    BackendKind kind() const override { return BackendKind::cuda; }
    std::string device_name() const override { return device_name_; }
    Status upload(const SceneData& scene) override;
    /// DeviceBuffers::grow on the backend's stream; the captured graphs, which hold the old
    /// buffers' addresses, are captured again on their next run (they match by pointers).
    Status grow(const SceneData& scene) override;
    /// Without profiling, each step of a named program (program_id) is one replay of a
    /// captured step graph, captured on the program's second step (its first is launched
    /// directly, as the one step of a program that changes every frame would cost more to
    /// capture than to launch; HMSM_CUDA_CAPTURE_AT_ONCE=1, read when the backend is created,
    /// captures on the first); an unnamed one is launched directly; with profiling, the launches (launch_plan.h: a run of
    /// dispatches over different groups is one batched launch) are enqueued one by one
    /// between events and every step is timed. A program of the walk that integrates ahead
    /// runs each step as `ahead` says (cuda_backend.cpp).
    Status run(std::span<const Dispatch> program, std::span<const RunStep> steps, uint64_t program_id = 0) override;
    Status read(BufferId id, uint64_t first, uint64_t count, void* dst, Scalar as) const override;
    Status write(BufferId id, uint64_t first, uint64_t count, const void* src, Scalar as) override;
    Status read_ranges(BufferId id, std::span<const ElementRange> ranges, void* dst, Scalar as) const override;
    Status write_ranges(BufferId id, std::span<const ElementRange> ranges, const void* src, Scalar as) override;
    Status move_elements(BufferId id, std::span<const ElementMove> moves) override;
    Status read_buffers(std::span<const BufferRangesRead> reads, Scalar as) const override;
    Status move_buffers(std::span<const BufferMoves> moves) override;
    Status copy_patterns(std::span<const BufferId> ids, uint64_t capacity, std::span<const MovePattern> patterns,
                         std::span<const PatternCopy> copies) override;
    Status request_read(uint32_t slot, BufferId id, uint64_t first, uint64_t count) const override;
    Result<const float*> take_read(uint32_t slot) const override;
    void set_profiling(bool enabled) override { profiling_ = enabled; }
    /// The path walk, integrating ahead unless HMSM_CUDA_WALK_AHEAD=0, and pattern copies unless
    /// HMSM_PATTERN_COPIES=0 (both read when the backend is created; for A/B measurements and
    /// tests).
    BackendCapabilities capabilities() const override {
        BackendCapabilities can;
        can.walks_ahead = walk_ahead_;
        can.prefers_path_walk = true;
        can.reads_async = true;
        can.grows_on_device = true;
        can.runs_listed_groups = true;
        can.copies_patterns = copies_patterns_;
        return can;
    }
    /// Steps run without their wind_force dispatches, taking the angles the step before
    /// integrated ahead (since the backend was created; for tests).
    uint64_t steps_taken_ahead() const { return steps_taken_ahead_; }
    /// Steps of a walk-ahead program run as the plain walk (AheadStep::plain; for tests).
    uint64_t steps_walked_plain() const { return steps_walked_plain_; }
    /// Step graphs captured, and steps launched directly rather than replayed (for tests).
    uint64_t graphs_captured() const { return graphs_captured_; }
    uint64_t steps_launched() const { return steps_launched_; }
    PassTimes pass_times() const override { return times_; }

    /// For `hmsm bench`'s roofline: the median of a few device-to-device copies of `bytes`
    /// between two scratch buffers, as (bytes read + bytes written) / device seconds.
    Result<double> measure_copy_bandwidth(uint64_t bytes) override;

    /// Later work runs on `stream` (nullptr: the backend's own), after the work on the previous
    /// stream has finished (waited for here when the stream changes).
    Status set_stream(cudaStream_t stream);
    /// false: run() returns once its steps are enqueued (include/hmsm/cuda.h enqueue_steps);
    /// true (the default): once they are complete.
    void set_waits_for_steps(bool wait) { waits_for_steps_ = wait; }
    int device() const { return device_; }
    const BufferPointers& device_pointers() const { return buffers_.pointers(); }

private:
    CudaBackend(int device, std::string name, cudaStream_t own_stream)
        : device_(device), device_name_(std::move(name)), own_stream_(own_stream), stream_(own_stream) {}
    /// The captured graph of `program` (named `program_id` where non-zero) over the current
    /// buffers, if one of the last few is.
    StepGraph* find_graph(std::span<const Dispatch> program, uint64_t program_id);
    /// Captures `program` in place of the least recently used graph.
    Result<StepGraph*> capture_graph(std::span<const Dispatch> program, uint64_t program_id);
    /// Whether the named step `step_id` runs for the first time of late (then remembered).
    bool first_run(uint64_t step_id);
    /// One step of `program` (named `step_id` where non-zero) launch by launch (launch_plan.h);
    /// `timed`: between events, its device times added to times_ (synchronizes).
    Status run_launches(std::span<const Dispatch> program, uint32_t slot, bool timed, uint64_t step_id = 0);
    Status make_current() const;

    int device_;
    std::string device_name_;
    cudaStream_t own_stream_;
    cudaStream_t stream_;
    DeviceBuffers buffers_;
    /// A program of the walk ahead replays up to three graphs (whole, without wind_force, as the
    /// plain walk), each over two buffer layouts (the state and its twin swapped or not): the
    /// least recently used of these is replaced.
    std::array<StepGraph, 6> graphs_;
    std::array<uint64_t, 6> graph_used_{};
    uint64_t graph_clock_ = 0;
    bool walk_ahead_ = true;
    /// Runs of dispatches over different groups are batched (launch_plan.h) unless
    /// HMSM_CUDA_BATCH_RUNS=0 (read when the backend is created).
    bool batch_runs_ = true;
    /// The program last run launch by launch (profiled, or run once), its launches and their
    /// table.
    std::vector<Dispatch> launched_program_;
    uint64_t launched_id_ = 0;  // its step id (0: none)
    LaunchPlan launched_plan_;
    LaunchTable launched_table_;
    /// The last program of the walk ahead that ran, and what its steps run instead where they
    /// take the angles integrated ahead or walk plain: derived once per program.
    AheadVariants ahead_;
    uint64_t ahead_id_ = 0;     // the program_id of the last program run (0: none given)
    bool walks_ahead_ = false;  // whether that program walks ahead (then ahead_ is its variants)
    uint64_t steps_taken_ahead_ = 0;   // steps that took the angles integrated ahead
    uint64_t steps_walked_plain_ = 0;  // steps_walked_plain()
    uint64_t graphs_captured_ = 0;     // graphs_captured()
    uint64_t steps_launched_ = 0;      // steps_launched()
    /// The named steps run once of late (launched directly; captured if they run again).
    std::array<uint64_t, 8> run_once_{};
    size_t run_once_next_ = 0;
    bool capture_at_once_ = false;  // HMSM_CUDA_CAPTURE_AT_ONCE=1
    bool copies_patterns_ = true;   // HMSM_PATTERN_COPIES=0 turns it off
    std::vector<cudaEvent_t> events_;  // profiling: one before and one after each dispatch
    bool profiling_ = false;
    bool waits_for_steps_ = true;
    PassTimes times_;
};

}  // namespace hmsm::detail::cuda
