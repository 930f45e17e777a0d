#include "cuda_backend.h"

#include "cuda_error.h"
#include "launch_dispatch.h"

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
    return std::unique_ptr<Backend>(std::move(backend));
}

CudaBackend::~CudaBackend() {
    (void)cudaSetDevice(device_);
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
    CUDA_TRY(cudaStreamSynchronize(stream_));  // finish what ran on the previous stream
    stream_ = stream ? stream : own_stream_;
    return {};
}

Status CudaBackend::upload(const SceneData& scene) {
    HMSM_TRY(make_current());
    next_state_ready_ = false;
    written_since_run_ = true;
    HMSM_TRY(buffers_.allocate(scene));
    return buffers_.upload(scene, stream_);
}

Status CudaBackend::read(BufferId id, uint64_t first, uint64_t count, void* dst, Scalar as) const {
    HMSM_TRY(make_current());
    return buffers_.read(id, first, count, dst, as, stream_);
}

Status CudaBackend::write(BufferId id, uint64_t first, uint64_t count, const void* src, Scalar as) {
    HMSM_TRY(make_current());
    HMSM_TRY(buffers_.write(id, first, count, src, as, stream_));
    // Anything a step reads may have changed, but for the wind table's step slots, which every
    // step() writes: those are kept on the host for next_slot_fits().
    if (id != BufferId::wind_table || first < HMSM_WIND_STEPS) {
        next_state_ready_ = false;
        written_since_run_ = true;
    }
    if (id != BufferId::wind_table) return {};
    step_slots_.resize(4 * (HMSM_WIND_TABLE_ELEMENTS - HMSM_WIND_STEPS));
    for (uint64_t e = std::max<uint64_t>(first, HMSM_WIND_STEPS); e < first + count; ++e)
        for (uint64_t i = 0; i < 4; ++i) {
            const uint64_t at = 4 * (e - first) + i;
            step_slots_[4 * (e - HMSM_WIND_STEPS) + i] =
                as == Scalar::f64 ? float(static_cast<const double*>(src)[at]) : static_cast<const float*>(src)[at];
        }
    return {};
}

Status CudaBackend::move_elements(BufferId id, std::span<const ElementMove> moves) {
    HMSM_TRY(make_current());
    next_state_ready_ = false;
    written_since_run_ = true;
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

Result<StepGraph*> CudaBackend::graph_for(std::span<const Dispatch> program) {
    size_t oldest = 0;
    for (size_t i = 0; i < graphs_.size(); ++i) {
        if (graphs_[i].matches(program, buffers_.pointers())) {
            graph_used_[i] = ++graph_clock_;
            return &graphs_[i];
        }
        if (graph_used_[i] < graph_used_[oldest]) oldest = i;
    }
    HMSM_TRY(graphs_[oldest].capture(program, buffers_.pointers(), stream_));
    graph_used_[oldest] = ++graph_clock_;
    return &graphs_[oldest];
}

bool CudaBackend::next_slot_fits(uint32_t slot) const {
    if (step_slots_.size() < 4 * HMSM_WIND_STEP_VEC4S * (uint64_t(slot) + 1)) return false;
    return std::equal(ahead_slot_.begin(), ahead_slot_.end(), step_slots_.begin() + 4 * HMSM_WIND_STEP_VEC4S * slot);
}

namespace {

/// After this many runs in a row each preceded by a live change (a force field that follows a
/// character), the first step of a run takes the plain walk, except every kRetryWalkAhead-th
/// run, which tries the walk ahead again; a run without a change before it ends the streak.
constexpr uint32_t kChangedRunsBeforePlain = 2;
constexpr uint32_t kRetryWalkAhead = 8;

}  // namespace

void CudaBackend::derive_ahead_variants(std::span<const Dispatch> program) {
    ahead_.whole.assign(program.begin(), program.end());
    ahead_.without_wind.clear();
    ahead_.plain.clear();
    for (Dispatch d : program) {
        if (d.pass != Pass::wind_force) ahead_.without_wind.push_back(d);
        // The plain walk: no top poses, and the walk ahead a plain forest walk (step_program.cpp
        // builds the same dispatch).
        if (is_top_poses_walk(d)) continue;
        if (is_walk_ahead(d)) {
            d.constants.kind = HMSM_DISPATCH_POSE_WALK;
            d.constants.level_count = 0;
        }
        ahead_.plain.push_back(d);
    }
}

// A program of the walk ahead leaves in chain_state_next the angles of the step after its own,
// from its pose and the next wind-table slot. The next step takes them (swapping the two state
// buffers) and runs without its wind_force dispatches where they are what it would integrate:
// within a run always (its slots follow one another); at the start of a run where the last run
// ran the same program, nothing but the wind table's step slots was written since, and
// next_slot_fits(). Otherwise it runs whole: wind_force integrates from chain_state, and the
// walk ahead again writes the step after. A whole step costs a little more than the plain walk
// (the top poses, the next angles written), so where changes come before step after step, the
// first step of a run walks plain (kChangedRunsBeforePlain).
Status CudaBackend::run(std::span<const Dispatch> program, std::span<const double> wind_x) {
    HMSM_TRY(make_current());
    times_ = {};
    if (wind_x.empty() || program.empty()) return {};
    const bool ahead = std::any_of(program.begin(), program.end(), [](const Dispatch& d) { return is_walk_ahead(d); });
    const bool same_program = ahead && same_dispatches(program, ahead_.whole);
    if (ahead && !same_program) derive_ahead_variants(program);  // once per program
    bool next_written = false;  // by the step before, in this run
    for (size_t k = 0; k < wind_x.size(); ++k) {
        const uint32_t slot = uint32_t(wind_x[k]);
        bool take = false, walk_plain = false;
        if (ahead && k == 0) {
            take = next_state_ready_ && same_program && next_slot_fits(slot);
            runs_changed_ = written_since_run_ ? runs_changed_ + 1 : 0;
            walk_plain = !take && runs_changed_ >= kChangedRunsBeforePlain && runs_changed_ % kRetryWalkAhead != 0;
        } else if (ahead) {
            take = next_written && slot == uint32_t(wind_x[k - 1]) + 1;
        }
        if (take) {
            buffers_.take_next_state();
            ++steps_taken_ahead_;
        }
        steps_walked_plain_ += walk_plain ? 1 : 0;
        next_written = ahead && !walk_plain;
        next_state_ready_ = false;  // being rewritten (or, without the walk ahead, left stale)
        written_since_run_ = false;
        const std::span<const Dispatch> step = take         ? std::span<const Dispatch>(ahead_.without_wind)
                                               : walk_plain ? std::span<const Dispatch>(ahead_.plain)
                                                            : program;
        if (profiling_) {
            HMSM_TRY(run_profiled(step, slot));
        } else {
            auto graph = graph_for(step);
            if (!graph) return graph.status();
            HMSM_TRY((*graph)->replay(float(slot), stream_));
        }
    }
    CUDA_TRY(cudaStreamSynchronize(stream_));
    times_.steps = profiling_ ? wind_x.size() : 0;
    if (!next_written) return {};
    // The slot the last step's top poses read (gpu_layout.h: the one after, at most the last).
    const uint32_t next = std::min<uint32_t>(uint32_t(wind_x.back()) + 1, HMSM_WIND_STEP_SLOTS - 1);
    ahead_slot_.assign(4 * HMSM_WIND_STEP_VEC4S, 0.0f);
    if (step_slots_.size() >= 4 * HMSM_WIND_STEP_VEC4S * (uint64_t(next) + 1))
        std::copy_n(step_slots_.begin() + 4 * HMSM_WIND_STEP_VEC4S * next, ahead_slot_.size(), ahead_slot_.begin());
    next_state_ready_ = true;
    return {};
}

Status CudaBackend::run_profiled(std::span<const Dispatch> program, uint32_t slot) {
    while (events_.size() < program.size() + 1) {
        cudaEvent_t event = nullptr;
        CUDA_TRY(cudaEventCreate(&event));
        events_.push_back(event);
    }
    CUDA_TRY(cudaEventRecord(events_[0], stream_));
    for (size_t j = 0; j < program.size(); ++j) {
        CUDA_TRY(launch_dispatch(program[j], buffers_.pointers(), float(slot), stream_));
        CUDA_TRY(cudaEventRecord(events_[j + 1], stream_));
    }
    CUDA_TRY(cudaEventSynchronize(events_[program.size()]));
    for (size_t j = 0; j < program.size(); ++j) {
        float milliseconds = 0.0f;
        CUDA_TRY(cudaEventElapsedTime(&milliseconds, events_[j], events_[j + 1]));
        times_.seconds[uint32_t(program[j].pass)] += 1e-3 * double(milliseconds);
    }
    return {};
}

}  // namespace cuda

Result<std::unique_ptr<Backend>> create_cuda_backend() { return cuda::CudaBackend::create(); }

}  // namespace hmsm::detail
