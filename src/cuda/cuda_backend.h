// The CUDA backend: device buffers, one stream (its own, or one an engine hands in through
// include/hmsm/cuda.h), the step program replayed as a CUDA graph, and per-pass device times
// from CUDA events when profiling.
#pragma once

#include "../backend.h"
#include "device_buffers.h"
#include "step_graph.h"

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
    /// Without profiling, each step is one replay of the captured step graph (captured on the
    /// first run() of a program); with profiling, the dispatches are launched one by one
    /// between events and every step is timed.
    Status run(std::span<const Dispatch> program, std::span<const double> wind_x) override;
    Status read(BufferId id, uint64_t first, uint64_t count, void* dst, Scalar as) const override;
    Status write(BufferId id, uint64_t first, uint64_t count, const void* src, Scalar as) override;
    Status move_elements(BufferId id, std::span<const ElementMove> moves) override;
    void set_profiling(bool enabled) override { profiling_ = enabled; }
    bool prefers_path_walk() const override { return true; }
    PassTimes pass_times() const override { return times_; }

    /// For `hmsm bench`'s roofline: the median of a few device-to-device copies of `bytes`
    /// between two scratch buffers, as (bytes read + bytes written) / device seconds.
    Result<double> measure_copy_bandwidth(uint64_t bytes) override;

    /// Later work runs on `stream` (nullptr: the backend's own). run() still returns only when
    /// its work on that stream is complete.
    Status set_stream(cudaStream_t stream);
    int device() const { return device_; }
    const BufferPointers& device_pointers() const { return buffers_.pointers(); }

private:
    CudaBackend(int device, std::string name, cudaStream_t own_stream, uint64_t fused_shared_limit)
        : device_(device), device_name_(std::move(name)), own_stream_(own_stream), stream_(own_stream),
          fused_shared_limit_(fused_shared_limit) {}
    Status run_graph(std::span<const Dispatch> program, std::span<const double> wind_x);
    Status run_profiled(std::span<const Dispatch> program, std::span<const double> wind_x);
    Status make_current() const;

    int device_;
    std::string device_name_;
    cudaStream_t own_stream_;
    cudaStream_t stream_;
    /// Shared memory a fused block may take (backend.h fused_shared_limit, read at creation).
    uint64_t fused_shared_limit_;
    DeviceBuffers buffers_;
    StepGraph graph_;
    std::vector<cudaEvent_t> events_;  // profiling: one before and one after each dispatch
    bool profiling_ = false;
    PassTimes times_;
};

}  // namespace hmsm::detail::cuda
