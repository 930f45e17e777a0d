#include "cuda_backend.h"

#include "cuda_error.h"
#include "launch_dispatch.h"
#include "../step_program.h"

#include <cuda_runtime_api.h>

#include <algorithm>
#include <cstdlib>
#include <string_view>

namespace hmsm::detail {
namespace cuda {

Result<std::unique_ptr<Backend>> CudaBackend::create() {
    int count = 0;
    const cudaError_t error = cudaGetDeviceCount(&count);
    if (error != cudaSuccess || count == 0) {
        (void)cudaGetLastError();
        return Status{ErrorCode::no_device,
                      std::string("cuda: no CUDA device is available (") +
                          (error != cudaSuccess ? cudaGetErrorName(error) : "0 devices") + ")"};
    }
    int device = 0;
    CUDA_TRY(cudaGetDevice(&device));
    cudaDeviceProp properties{};
    CUDA_TRY(cudaGetDeviceProperties(&properties, device));
    CUDA_TRY(cudaSetDevice(device));
    cudaStream_t stream = nullptr;
    CUDA_TRY(cudaStreamCreateWithFlags(&stream, cudaStreamNonBlocking));
    auto backend = std::unique_ptr<CudaBackend>(new CudaBackend(device, properties.name, stream));
    const char* ahead = std::getenv("HMSM_CUDA_WALK_AHEAD");
    backend->walk_ahead_ = !(ahead && std::string_view(ahead) == "0");
    backend->batch_runs_ = batch_runs_enabled();
    const char* at_once = std::getenv("HMSM_CUDA_CAPTURE_AT_ONCE");
    backend->capture_at_once_ = at_once && std::string_view(at_once) == "1";
    backend->copies_patterns_ = pattern_copies_enabled();
    return std::unique_ptr<Backend>(std::move(backend));
}

CudaBackend::~CudaBackend() {
    (void)cudaSetDevice(device_);
    (void)cudaStreamSynchronize(stream_);  // nothing enqueued may outlive the buffers
    for (cudaEvent_t event : events_) (void)cudaEventDestroy(event);
    if (own_stream_) (void)cudaStreamDestroy(own_stream_);
    // buffers_ and graphs_ release themselves.
}

Status CudaBackend::make_current() const {
    CUDA_TRY(cudaSetDevice(device_));
    return {};
}

Status CudaBackend::set_stream(cudaStream_t stream) {
    HMSM_TRY(make_current());
    const cudaStream_t next = stream ? stream : own_stream_;
    if (next == stream_) return {};
    CUDA_TRY(cudaStreamSynchronize(stream_));  // finish what ran on the previous stream
    stream_ = next;
    return {};
}

Status CudaBackend::upload(const SceneData& scene) {
    HMSM_TRY(make_current());
    CUDA_TRY(cudaStreamSynchronize(stream_));  // enqueued work may still use the old buffers
    HMSM_TRY(buffers_.allocate(scene));
    return buffers_.upload(scene, stream_);
}

Status CudaBackend::grow(const SceneData& scene) {
    HMSM_TRY(make_current());
    return buffers_.grow(scene, stream_);
}

Status CudaBackend::read(BufferId id, uint64_t first, uint64_t count, void* dst, Scalar as) const {
    HMSM_TRY(make_current());
    return buffers_.read(id, first, count, dst, as, stream_);
}

Status CudaBackend::write(BufferId id, uint64_t first, uint64_t count, const void* src, Scalar as) {
    HMSM_TRY(make_current());
    return buffers_.write(id, first, count, src, as, stream_);
}

Status CudaBackend::request_read(uint32_t slot, BufferId id, uint64_t first, uint64_t count) const {
    HMSM_TRY(make_current());
    return buffers_.request_read(slot, id, first, count, stream_);
}

Result<const float*> CudaBackend::take_read(uint32_t slot) const {
    HMSM_TRY(make_current());
    return buffers_.take_read(slot);
}

Status CudaBackend::read_ranges(BufferId id, std::span<const ElementRange> ranges, void* dst, Scalar as) const {
    HMSM_TRY(make_current());
    return buffers_.read_ranges(id, ranges, dst, as, stream_);
}

Status CudaBackend::write_ranges(BufferId id, std::span<const ElementRange> ranges, const void* src, Scalar as) {
    HMSM_TRY(make_current());
    return buffers_.write_ranges(id, ranges, src, as, stream_);
}

Status CudaBackend::read_buffers(std::span<const BufferRangesRead> reads, Scalar as) const {
    HMSM_TRY(make_current());
    return buffers_.read_buffers(reads, as, stream_);
}

Status CudaBackend::move_buffers(std::span<const BufferMoves> moves) {
    HMSM_TRY(make_current());
    return buffers_.move_buffers(moves, stream_);
}

Status CudaBackend::copy_patterns(std::span<const BufferId> ids, uint64_t capacity,
                                  std::span<const MovePattern> patterns, std::span<const PatternCopy> copies) {
    if (!copies_patterns_) return Backend::copy_patterns(ids, capacity, patterns, copies);
    HMSM_TRY(make_current());
    return buffers_.copy_patterns(ids, capacity, patterns, copies, stream_);
}

Status CudaBackend::move_elements(BufferId id, std::span<const ElementMove> moves) {
    HMSM_TRY(make_current());
    return buffers_.move(id, moves, stream_);
}

Result<double> CudaBackend::measure_copy_bandwidth(uint64_t bytes) {
    HMSM_TRY(make_current());
    void* source = nullptr;
    void* target = nullptr;
    cudaEvent_t start = nullptr, stop = nullptr;
    std::vector<float> milliseconds;
    auto measure = [&]() -> Status {
        CUDA_TRY(cudaMalloc(&source, bytes));
        CUDA_TRY(cudaMalloc(&target, bytes));
        CUDA_TRY(cudaEventCreate(&start));
        CUDA_TRY(cudaEventCreate(&stop));
        CUDA_TRY(cudaMemsetAsync(source, 0x3c, bytes, stream_));
        CUDA_TRY(cudaMemcpyAsync(target, source, bytes, cudaMemcpyDeviceToDevice, stream_));  // warm-up
        for (int repeat = 0; repeat < 7; ++repeat) {
            CUDA_TRY(cudaEventRecord(start, stream_));
            CUDA_TRY(cudaMemcpyAsync(target, source, bytes, cudaMemcpyDeviceToDevice, stream_));
            CUDA_TRY(cudaEventRecord(stop, stream_));
            CUDA_TRY(cudaEventSynchronize(stop));
            float ms = 0.0f;
            CUDA_TRY(cudaEventElapsedTime(&ms, start, stop));
            milliseconds.push_back(ms);
        }
        return {};
    };
    const Status status = measure();
    if (start) (void)cudaEventDestroy(start);
    if (stop) (void)cudaEventDestroy(stop);
    if (source) (void)cudaFree(source);
    if (target) (void)cudaFree(target);
    if (!status.ok()) return status;
    std::sort(milliseconds.begin(), milliseconds.end());
    const double median_seconds = 1e-3 * double(milliseconds[milliseconds.size() / 2]);
    if (!(median_seconds > 0.0)) return Status{ErrorCode::device_error, "cuda: copy took no measurable time"};
    return 2.0 * double(bytes) / median_seconds;
}

StepGraph* CudaBackend::find_graph(std::span<const Dispatch> program, uint64_t program_id) {
    for (size_t i = 0; i < graphs_.size(); ++i) {
        if (graphs_[i].matches(program, buffers_.pointers(), program_id)) {
            graph_used_[i] = ++graph_clock_;
            return &graphs_[i];
        }
    }
    return nullptr;
}

Result<StepGraph*> CudaBackend::capture_graph(std::span<const Dispatch> program, uint64_t program_id) {
    size_t oldest = 0;
    for (size_t i = 1; i < graphs_.size(); ++i)
        if (graph_used_[i] < graph_used_[oldest]) oldest = i;
    HMSM_TRY(graphs_[oldest].capture(program, buffers_.pointers(), batch_runs_, stream_, program_id));
    graph_used_[oldest] = ++graph_clock_;
    ++graphs_captured_;
    return &graphs_[oldest];
}

bool CudaBackend::first_run(uint64_t step_id) {
    if (capture_at_once_) return false;
    if (std::find(run_once_.begin(), run_once_.end(), step_id) != run_once_.end()) return false;
    run_once_[run_once_next_] = step_id;
    run_once_next_ = (run_once_next_ + 1) % run_once_.size();
    return true;
}

// A program of the walk ahead leaves in chain_state_next the angles of the step after its own,
// from its pose and the next wind-table slot. A step that takes them (AheadStep::take, the step
// layer's decision) swaps the two state buffers and runs without its wind_force dispatches; a
// plain one runs the plain walk, a whole one the program.
Status CudaBackend::run(std::span<const Dispatch> program, std::span<const RunStep> steps, uint64_t program_id) {
    HMSM_TRY(make_current());
    times_ = {};
    if (steps.empty() || program.empty()) return {};
    // Derived once per program; a program named by an id is recognized without looking at its
    // dispatches (a forest's step program has thousands).
    if (program_id == 0 || program_id != ahead_id_) {
        walks_ahead_ = std::any_of(program.begin(), program.end(), [](const Dispatch& d) { return is_walk_ahead(d); });
        if (walks_ahead_ && !same_program(program, program_id, ahead_.whole, ahead_id_)) ahead_variants(program, ahead_);
        ahead_id_ = program_id;
    }
    const bool walks_ahead = walks_ahead_;
    for (const RunStep& run_step : steps) {
        const uint32_t slot = run_step.wind_slot;
        const AheadStep how = walks_ahead ? run_step.ahead : AheadStep::whole;
        if (how == AheadStep::take) {
            buffers_.take_next_state();
            ++steps_taken_ahead_;
        }
        steps_walked_plain_ += how == AheadStep::plain ? 1 : 0;
        const std::span<const Dispatch> step = how == AheadStep::take    ? std::span<const Dispatch>(ahead_.without_wind)
                                               : how == AheadStep::plain ? std::span<const Dispatch>(ahead_.plain)
                                                                         : program;
        // Each variant of a named program is a program of its own, with an id of its own.
        const uint64_t variant = how == AheadStep::take ? 1 : how == AheadStep::plain ? 2 : 0;
        const uint64_t step_id = program_id != 0 ? 3 * program_id + variant : 0;
        StepGraph* graph = profiling_ || step_id == 0 ? nullptr : find_graph(step, step_id);
        // Timed launch by launch, or a program run once (a pose at rest after a live change,
        // the first step after a level switch): capturing a graph would cost more than it
        // saves and evict a step's. A named program is captured on its second step.
        if (!graph && (profiling_ || step_id == 0 || first_run(step_id))) {
            HMSM_TRY(run_launches(step, slot, profiling_, step_id));
            continue;
        }
        if (!graph) {
            auto captured = capture_graph(step, step_id);
            if (!captured) return captured.status();
            graph = *captured;
        }
        HMSM_TRY(graph->replay(slot, stream_));
    }
    if (waits_for_steps_ || profiling_) CUDA_TRY(cudaStreamSynchronize(stream_));
    times_.steps = profiling_ ? steps.size() : 0;
    return {};
}

Status CudaBackend::run_launches(std::span<const Dispatch> program, uint32_t slot, bool timed, uint64_t step_id) {
    ++steps_launched_;
    const bool same = same_program(program, step_id, launched_program_, launched_id_);
    launched_id_ = step_id;
    if (!same || launched_plan_.launches.empty()) {
        launched_program_.assign(program.begin(), program.end());
        plan_launches(launched_program_, batch_runs_, max_launch_blocks(), launched_plan_);
        HMSM_TRY(launched_table_.upload(launched_plan_, stream_));
    }
    const std::vector<PlannedLaunch>& launches = launched_plan_.launches;
    if (!timed) {
        for (const PlannedLaunch& launch : launches)
            CUDA_TRY(enqueue_launch(launched_plan_, launch, launched_program_, launched_table_, buffers_.pointers(),
                                    slot, stream_));
        return {};
    }
    while (events_.size() < launches.size() + 1) {
        cudaEvent_t event = nullptr;
        CUDA_TRY(cudaEventCreate(&event));
        events_.push_back(event);
    }
    CUDA_TRY(cudaEventRecord(events_[0], stream_));
    for (size_t j = 0; j < launches.size(); ++j) {
        CUDA_TRY(enqueue_launch(launched_plan_, launches[j], launched_program_, launched_table_, buffers_.pointers(),
                                slot, stream_));
        CUDA_TRY(cudaEventRecord(events_[j + 1], stream_));
    }
    CUDA_TRY(cudaEventSynchronize(events_[launches.size()]));
    for (size_t j = 0; j < launches.size(); ++j) {
        float milliseconds = 0.0f;
        CUDA_TRY(cudaEventElapsedTime(&milliseconds, events_[j], events_[j + 1]));
        times_.seconds[uint32_t(launches[j].pass)] += 1e-3 * double(milliseconds);
    }
    return {};
}

}  // namespace cuda

Result<std::unique_ptr<Backend>> create_cuda_backend() { return cuda::CudaBackend::create(); }

}  // namespace hmsm::detail
