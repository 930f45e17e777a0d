// The engine paths of hmsm bench --frames: a CUDA stream of the engine's own (the CLI links a
// CUDA runtime of its own for it, as an engine would) and a Vulkan command buffer of the
// engine's own, recorded and submitted through the loader's entry points.
#include "bench_frames.h"

#ifdef HMSM_BENCH_CUDA_STREAM
#include <hmsm/cuda.h>

#include <cuda_runtime_api.h>
#endif

#ifdef HMSM_HAVE_VULKAN
#include <hmsm/vulkan.h>

#include <dlfcn.h>
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

#ifdef HMSM_HAVE_VULKAN
/// hmsm::vulkan::record_steps into a command buffer the engine owns, between two timestamps of
/// the engine's; the frame ends when its submission's fence signals.
class VulkanRecord final : public FrameDriver {
public:
    static std::unique_ptr<FrameDriver> create(Simulation& simulation, uint32_t steps) {
        if (simulation.backend_kind() != BackendKind::vulkan) return nullptr;
        auto handles = hmsm::vulkan::device_handles(simulation);
        if (!handles) return nullptr;
        std::unique_ptr<VulkanRecord> driver(new VulkanRecord(*handles, steps));
        return driver->ready() ? std::move(driver) : nullptr;
    }
    ~VulkanRecord() override {
        if (queries_) destroy_queries_(h_.device, queries_, nullptr);
        if (fence_) destroy_fence_(h_.device, fence_, nullptr);
        if (pool_) destroy_pool_(h_.device, pool_, nullptr);
        if (library_) dlclose(library_);
    }
    const char* path() const override { return "record"; }
    Status begin(Simulation&) override {
        VkCommandBufferBeginInfo begin{};
        begin.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO;
        begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
        if (reset_buffer_(buffer_, 0) != VK_SUCCESS || begin_(buffer_, &begin) != VK_SUCCESS)
            return {ErrorCode::device_error, "vulkan: cannot begin the frame's command buffer"};
        reset_queries_(buffer_, queries_, 0, 2);
        timestamp_(buffer_, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, queries_, 0);
        return {};
    }
    Status call(Simulation& simulation) override { return hmsm::vulkan::record_steps(simulation, buffer_, steps_); }
    Status finish(Simulation&) override {
        timestamp_(buffer_, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, queries_, 1);
        if (end_(buffer_) != VK_SUCCESS) return {ErrorCode::device_error, "vulkan: cannot end the command buffer"};
        VkSubmitInfo submit{};
        submit.sType = VK_STRUCTURE_TYPE_SUBMIT_INFO;
        submit.commandBufferCount = 1;
        submit.pCommandBuffers = &buffer_;
        uint64_t ticks[2] = {};
        if (submit_(h_.queue, 1, &submit, fence_) != VK_SUCCESS ||
            wait_(h_.device, 1, &fence_, VK_TRUE, UINT64_MAX) != VK_SUCCESS || reset_fence_(h_.device, 1, &fence_) != VK_SUCCESS ||
            query_results_(h_.device, queries_, 0, 2, sizeof ticks, ticks, sizeof(uint64_t),
                           VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT) != VK_SUCCESS)
            return {ErrorCode::device_error, "vulkan: the frame's submission failed"};
        device_seconds_ = double((ticks[1] - ticks[0]) & tick_mask_) * tick_ns_ * 1e-9;
        return {};
    }
    std::optional<double> device_seconds() const override { return device_seconds_; }

private:
    VulkanRecord(const hmsm::vulkan::DeviceHandles& handles, uint32_t steps) : h_(handles), steps_(steps) {
        library_ = dlopen("libvulkan.so.1", RTLD_NOW | RTLD_LOCAL);
        if (!library_) return;
        auto device_proc = reinterpret_cast<PFN_vkGetDeviceProcAddr>(dlsym(library_, "vkGetDeviceProcAddr"));
        auto properties =
            reinterpret_cast<PFN_vkGetPhysicalDeviceProperties>(dlsym(library_, "vkGetPhysicalDeviceProperties"));
        auto family_properties = reinterpret_cast<PFN_vkGetPhysicalDeviceQueueFamilyProperties>(
            dlsym(library_, "vkGetPhysicalDeviceQueueFamilyProperties"));
        if (!device_proc || !properties || !family_properties) return;
        auto load = [&](auto& fn, const char* name) { fn = reinterpret_cast<std::decay_t<decltype(fn)>>(device_proc(h_.device, name)); };
        PFN_vkCreateCommandPool create_pool = nullptr;
        PFN_vkAllocateCommandBuffers allocate = nullptr;
        PFN_vkCreateFence create_fence = nullptr;
        PFN_vkCreateQueryPool create_queries = nullptr;
        load(create_pool, "vkCreateCommandPool");
        load(allocate, "vkAllocateCommandBuffers");
        load(create_fence, "vkCreateFence");
        load(create_queries, "vkCreateQueryPool");
        load(destroy_pool_, "vkDestroyCommandPool");
        load(destroy_fence_, "vkDestroyFence");
        load(destroy_queries_, "vkDestroyQueryPool");
        load(reset_buffer_, "vkResetCommandBuffer");
        load(begin_, "vkBeginCommandBuffer");
        load(end_, "vkEndCommandBuffer");
        load(reset_queries_, "vkCmdResetQueryPool");
        load(timestamp_, "vkCmdWriteTimestamp");
        load(query_results_, "vkGetQueryPoolResults");
        load(submit_, "vkQueueSubmit");
        load(wait_, "vkWaitForFences");
        load(reset_fence_, "vkResetFences");
        if (!create_pool || !allocate || !create_fence || !create_queries || !destroy_pool_ || !destroy_fence_ ||
            !destroy_queries_ || !reset_buffer_ || !begin_ || !end_ || !reset_queries_ || !timestamp_ ||
            !query_results_ || !submit_ || !wait_ || !reset_fence_)
            return;
        // The queue's timestamps: their period and valid bits (none: no device times to give).
        VkPhysicalDeviceProperties device{};
        properties(h_.physical_device, &device);
        uint32_t families = 0;
        family_properties(h_.physical_device, &families, nullptr);
        std::vector<VkQueueFamilyProperties> family(families);
        family_properties(h_.physical_device, &families, family.data());
        const uint32_t valid_bits = h_.queue_family_index < families ? family[h_.queue_family_index].timestampValidBits : 0;
        if (valid_bits == 0 || device.limits.timestampPeriod <= 0.0f) return;
        tick_mask_ = valid_bits >= 64 ? ~uint64_t(0) : (uint64_t(1) << valid_bits) - 1;
        tick_ns_ = double(device.limits.timestampPeriod);
        VkCommandPoolCreateInfo pool{};
        pool.sType = VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO;
        pool.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
        pool.queueFamilyIndex = h_.queue_family_index;
        if (create_pool(h_.device, &pool, nullptr, &pool_) != VK_SUCCESS) return;
        VkCommandBufferAllocateInfo info{};
        info.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO;
        info.commandPool = pool_;
        info.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
        info.commandBufferCount = 1;
        if (allocate(h_.device, &info, &buffer_) != VK_SUCCESS) return;
        VkQueryPoolCreateInfo queries{};
        queries.sType = VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO;
        queries.queryType = VK_QUERY_TYPE_TIMESTAMP;
        queries.queryCount = 2;
        if (create_queries(h_.device, &queries, nullptr, &queries_) != VK_SUCCESS) queries_ = VK_NULL_HANDLE;
        VkFenceCreateInfo fence{};
        fence.sType = VK_STRUCTURE_TYPE_FENCE_CREATE_INFO;
        if (create_fence(h_.device, &fence, nullptr, &fence_) != VK_SUCCESS) fence_ = VK_NULL_HANDLE;
    }
    bool ready() const { return fence_ != VK_NULL_HANDLE && buffer_ != VK_NULL_HANDLE && queries_ != VK_NULL_HANDLE; }

    hmsm::vulkan::DeviceHandles h_;
    uint32_t steps_;
    void* library_ = nullptr;
    VkCommandPool pool_ = VK_NULL_HANDLE;
    VkCommandBuffer buffer_ = VK_NULL_HANDLE;
    VkFence fence_ = VK_NULL_HANDLE;
    VkQueryPool queries_ = VK_NULL_HANDLE;
    uint64_t tick_mask_ = 0;
    double tick_ns_ = 0.0;
    double device_seconds_ = 0.0;
    PFN_vkDestroyCommandPool destroy_pool_ = nullptr;
    PFN_vkDestroyFence destroy_fence_ = nullptr;
    PFN_vkDestroyQueryPool destroy_queries_ = nullptr;
    PFN_vkResetCommandBuffer reset_buffer_ = nullptr;
    PFN_vkBeginCommandBuffer begin_ = nullptr;
    PFN_vkEndCommandBuffer end_ = nullptr;
    PFN_vkCmdResetQueryPool reset_queries_ = nullptr;
    PFN_vkCmdWriteTimestamp timestamp_ = nullptr;
    PFN_vkGetQueryPoolResults query_results_ = nullptr;
    PFN_vkQueueSubmit submit_ = nullptr;
    PFN_vkWaitForFences wait_ = nullptr;
    PFN_vkResetFences reset_fence_ = nullptr;
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
#ifdef HMSM_HAVE_VULKAN
    if (auto driver = VulkanRecord::create(simulation, steps)) drivers.push_back(std::move(driver));
#endif
    return drivers;
}

}  // namespace hmsm::cli::bench
