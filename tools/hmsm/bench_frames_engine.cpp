// The engine paths of hmsm bench --frames: a CUDA stream of the engine's own (the CLI links a
// CUDA runtime of its own for it, as an engine would) and a Vulkan command buffer of the
// engine's own, in the examples' engine frame loop through the system Vulkan loader (which the
// CLI links for it, as an engine would; hmsm keeps its own entry points private).
#include "bench_frames.h"

#ifdef HMSM_BENCH_CUDA_STREAM
#include <hmsm/cuda.h>

#include <cuda_runtime_api.h>
#endif

#ifdef HMSM_BENCH_VULKAN_RECORD
// The engine calls the loader's entry points (hmsm's targets define VK_NO_PROTOTYPES for the
// sources that use hmsm's private volk); this is the first Vulkan header of this file.
#undef VK_NO_PROTOTYPES
#include "../../examples/common/engine_vulkan.h"

#include <hmsm/vulkan.h>
#endif

namespace hmsm::cli::bench {
namespace {

#ifdef HMSM_BENCH_CUDA_STREAM
/// hmsm::cuda::enqueue_steps on a stream the engine owns, between two events of the engine's;
/// the frame ends when the stream has drained.
class CudaEnqueue final : public FrameDriver {
public:
    static std::unique_ptr<FrameDriver> create(Simulation& simulation, uint32_t steps) {
        if (simulation.backend_kind() != BackendKind::cuda) return nullptr;
        std::unique_ptr<CudaEnqueue> driver(new CudaEnqueue(simulation, steps));
        if (cudaStreamCreateWithFlags(&driver->stream_, cudaStreamNonBlocking) != cudaSuccess ||
            cudaEventCreate(&driver->started_) != cudaSuccess || cudaEventCreate(&driver->ended_) != cudaSuccess)
            return nullptr;
        return driver;
    }
    ~CudaEnqueue() override {
        if (stream_) (void)hmsm::cuda::set_stream(simulation_, nullptr);  // hmsm stops using the stream first
        if (started_) (void)cudaEventDestroy(started_);
        if (ended_) (void)cudaEventDestroy(ended_);
        if (stream_) (void)cudaStreamDestroy(stream_);
    }
    const char* path() const override { return "enqueue"; }
    Status begin(Simulation&) override { return check(cudaEventRecord(started_, stream_), "cudaEventRecord"); }
    Status call(Simulation& simulation) override { return hmsm::cuda::enqueue_steps(simulation, stream_, steps_); }
    Status finish(Simulation&) override {
        HMSM_TRY(check(cudaEventRecord(ended_, stream_), "cudaEventRecord"));
        HMSM_TRY(check(cudaStreamSynchronize(stream_), "cudaStreamSynchronize"));
        float ms = 0.0f;
        HMSM_TRY(check(cudaEventElapsedTime(&ms, started_, ended_), "cudaEventElapsedTime"));
        device_seconds_ = double(ms) * 1e-3;
        return {};
    }
    std::optional<double> device_seconds() const override { return device_seconds_; }

private:
    CudaEnqueue(Simulation& simulation, uint32_t steps) : simulation_(simulation), steps_(steps) {}
    static Status check(cudaError_t error, const char* what) {
        if (error == cudaSuccess) return {};
        return {ErrorCode::device_error, std::string(what) + ": " + cudaGetErrorName(error)};
    }
    Simulation& simulation_;
    uint32_t steps_;
    cudaStream_t stream_ = nullptr;
    cudaEvent_t started_ = nullptr, ended_ = nullptr;
    double device_seconds_ = 0.0;
};
#endif

#ifdef HMSM_BENCH_VULKAN_RECORD
/// hmsm::vulkan::record_steps into a command buffer the engine owns, between two timestamps of
/// the engine's; the frame ends when its submission's fence signals. The engine's frame loop is
/// the examples' (examples/common/engine_vulkan.h Frames, as examples/engine_loop runs it), one
/// frame in flight so that each frame's outputs are ready when it ends.
class VulkanRecord final : public FrameDriver {
public:
    static std::unique_ptr<FrameDriver> create(Simulation& simulation, uint32_t steps) {
        if (simulation.backend_kind() != BackendKind::vulkan) return nullptr;
        auto handles = hmsm::vulkan::device_handles(simulation);
        if (!handles) return nullptr;
        try {
            return std::unique_ptr<FrameDriver>(new VulkanRecord(*handles, steps));
        } catch (const std::exception&) {
            return nullptr;  // no timestamps on this queue, or the device refused the objects
        }
    }
    ~VulkanRecord() override {
        frames_.reset();  // waits for the queue first
        vkDestroyQueryPool(h_.device, queries_, nullptr);
    }
    const char* path() const override { return "record"; }
    Status begin(Simulation&) override {
        return guarded([&] {
            command_buffer_ = frames_->begin(frame_);
            vkCmdResetQueryPool(command_buffer_, queries_, 0, 2);
            vkCmdWriteTimestamp(command_buffer_, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, queries_, 0);
        });
    }
    Status call(Simulation& simulation) override {
        return hmsm::vulkan::record_steps(simulation, command_buffer_, steps_);
    }
    Status finish(Simulation&) override {
        return guarded([&] {
            vkCmdWriteTimestamp(command_buffer_, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, queries_, 1);
            frames_->submit(frame_);
            frames_->wait(frame_++);
            uint64_t ticks[2] = {};
            engine::check(vkGetQueryPoolResults(h_.device, queries_, 0, 2, sizeof ticks, ticks, sizeof(uint64_t),
                                                VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT),
                          "vkGetQueryPoolResults");
            device_seconds_ = double((ticks[1] - ticks[0]) & tick_mask_) * tick_ns_ * 1e-9;
        });
    }
    std::optional<double> device_seconds() const override { return device_seconds_; }

private:
    VulkanRecord(const hmsm::vulkan::DeviceHandles& handles, uint32_t steps) : h_(handles), steps_(steps) {
        // The queue's timestamps: their period and valid bits.
        VkPhysicalDeviceProperties device{};
        vkGetPhysicalDeviceProperties(h_.physical_device, &device);
        uint32_t families = 0;
        vkGetPhysicalDeviceQueueFamilyProperties(h_.physical_device, &families, nullptr);
        std::vector<VkQueueFamilyProperties> family(families);
        vkGetPhysicalDeviceQueueFamilyProperties(h_.physical_device, &families, family.data());
        const uint32_t valid_bits = h_.queue_family_index < families ? family[h_.queue_family_index].timestampValidBits : 0;
        if (valid_bits == 0 || device.limits.timestampPeriod <= 0.0f) throw engine::VulkanError("no timestamps");
        tick_mask_ = valid_bits >= 64 ? ~uint64_t(0) : (uint64_t(1) << valid_bits) - 1;
        tick_ns_ = double(device.limits.timestampPeriod);
        VkQueryPoolCreateInfo queries{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
        queries.queryType = VK_QUERY_TYPE_TIMESTAMP;
        queries.queryCount = 2;
        engine::check(vkCreateQueryPool(h_.device, &queries, nullptr, &queries_), "vkCreateQueryPool");
        try {
            frames_ = std::make_unique<engine::Frames>(h_.device, h_.queue, h_.queue_family_index, 1);
        } catch (...) {
            vkDestroyQueryPool(h_.device, queries_, nullptr);
            throw;
        }
    }
    /// Runs `body`, a failed Vulkan call in it becoming an error.
    template <class Body>
    static Status guarded(Body&& body) {
        try {
            body();
            return {};
        } catch (const engine::VulkanError& e) {
            return {ErrorCode::device_error, std::string("vulkan: the engine's frame: ") + e.what()};
        }
    }

    hmsm::vulkan::DeviceHandles h_;
    uint32_t steps_;
    std::unique_ptr<engine::Frames> frames_;
    VkQueryPool queries_ = VK_NULL_HANDLE;
    VkCommandBuffer command_buffer_ = VK_NULL_HANDLE;
    uint64_t frame_ = 0;
    uint64_t tick_mask_ = 0;
    double tick_ns_ = 0.0;
    double device_seconds_ = 0.0;
};
#endif

}  // namespace

std::vector<std::unique_ptr<FrameDriver>> engine_drivers(Simulation& simulation, uint32_t steps) {
    std::vector<std::unique_ptr<FrameDriver>> drivers;
    (void)simulation;
    (void)steps;
#ifdef HMSM_BENCH_CUDA_STREAM
    if (auto driver = CudaEnqueue::create(simulation, steps)) drivers.push_back(std::move(driver));
#endif
#ifdef HMSM_BENCH_VULKAN_RECORD
    if (auto driver = VulkanRecord::create(simulation, steps)) drivers.push_back(std::move(driver));
#endif
    return drivers;
}

}  // namespace hmsm::cli::bench
