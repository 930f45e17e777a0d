#include "cuda_backend.h"

#include "cuda_error.h"
#include "launch_dispatch.h"

#include <cuda_runtime_api.h>

#include <algorithm>

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
    // The fused kernel's rounds may take up to the opt-in maximum of shared memory per block.
    int shared_optin = 0;
    CUDA_TRY(cudaDeviceGetAttribute(&shared_optin, cudaDevAttrMaxSharedMemoryPerBlockOptin, device));
    const uint64_t fused_shared = fused_shared_limit(uint64_t(shared_optin));
    CUDA_TRY(allow_fused_shared(fused_shared));
    cudaStream_t stream = nullptr;
    CUDA_TRY(cudaStreamCreateWithFlags(&stream, cudaStreamNonBlocking));
    return std::unique_ptr<Backend>(
        new CudaBackend(device, properties.name, stream, fused_shared));
}

CudaBackend::~CudaBackend() {
    (void)cudaSetDevice(device_);
    for (cudaEvent_t event : events_) (void)cudaEventDestroy(event);
    if (own_stream_) (void)cudaStreamDestroy(own_stream_);
    // buffers_ and graph_ release themselves.
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
    HMSM_TRY(buffers_.allocate(scene));
    return buffers_.upload(scene, stream_);
}

Status CudaBackend::read(BufferId id, uint64_t first, uint64_t count, void* dst, Scalar as) const {
    HMSM_TRY(make_current());
    return buffers_.read(id, first, count, dst, as, stream_);
}

Status CudaBackend::write(BufferId id, uint64_t first, uint64_t count, const void* src, Scalar as) {
    HMSM_TRY(make_current());
    return buffers_.write(id, first, count, src, as, stream_);
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

Status CudaBackend::run(std::span<const Dispatch> program, std::span<const double> wind_x) {
    HMSM_TRY(make_current());
    times_ = {};
    if (wind_x.empty() || program.empty()) return {};
    return profiling_ ? run_profiled(program, wind_x) : run_graph(program, wind_x);
}

Status CudaBackend::run_graph(std::span<const Dispatch> program, std::span<const double> wind_x) {
    if (!graph_.matches(program, buffers_.pointers()))
        HMSM_TRY(graph_.capture(program, buffers_.pointers(), stream_, fused_shared_limit_));
    for (double x : wind_x) HMSM_TRY(graph_.replay(float(x), stream_));
    CUDA_TRY(cudaStreamSynchronize(stream_));
    return {};
}

Status CudaBackend::run_profiled(std::span<const Dispatch> program, std::span<const double> wind_x) {
    while (events_.size() < program.size() + 1) {
        cudaEvent_t event = nullptr;
        CUDA_TRY(cudaEventCreate(&event));
        events_.push_back(event);
    }
    for (double x : wind_x) {
        CUDA_TRY(cudaEventRecord(events_[0], stream_));
        for (size_t j = 0; j < program.size(); ++j) {
            CUDA_TRY(launch_dispatch(program[j], buffers_.pointers(), float(x), stream_, fused_shared_limit_));
            CUDA_TRY(cudaEventRecord(events_[j + 1], stream_));
        }
        CUDA_TRY(cudaEventSynchronize(events_[program.size()]));
        for (size_t j = 0; j < program.size(); ++j) {
            float milliseconds = 0.0f;
            CUDA_TRY(cudaEventElapsedTime(&milliseconds, events_[j], events_[j + 1]));
            times_.seconds[uint32_t(program[j].pass)] += 1e-3 * double(milliseconds);
        }
    }
    CUDA_TRY(cudaStreamSynchronize(stream_));
    times_.steps = wind_x.size();
    return {};
}

}  // namespace cuda

Result<std::unique_ptr<Backend>> create_cuda_backend() { return cuda::CudaBackend::create(); }

}  // namespace hmsm::detail
