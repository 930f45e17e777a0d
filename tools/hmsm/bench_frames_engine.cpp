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
/// hmsm::cuda::enqueue_steps on a stream the engine owns; the frame ends when it has drained.
class CudaEnqueue final : public FrameDriver {
public:
    static std::unique_ptr<FrameDriver> create(Simulation& simulation) {
        if (simulation.backend_kind() != BackendKind::cuda) return nullptr;
        cudaStream_t stream = nullptr;
        if (cudaStreamCreateWithFlags(&stream, cudaStreamNonBlocking) != cudaSuccess) return nullptr;
        return std::unique_ptr<FrameDriver>(new CudaEnqueue(simulation, stream));
    }
    ~CudaEnqueue() override {
        (void)hmsm::cuda::set_stream(simulation_, nullptr);  // hmsm stops using the stream first
        (void)cudaStreamDestroy(stream_);
    }
    const char* path() const override { return "enqueue"; }
    Status call(Simulation& simulation) override { return hmsm::cuda::enqueue_steps(simulation, stream_, 1); }
    Status finish(Simulation&) override {
        const cudaError_t error = cudaStreamSynchronize(stream_);
        if (error != cudaSuccess)
            return {ErrorCode::device_error, std::string("cudaStreamSynchronize: ") + cudaGetErrorName(error)};
        return {};
    }

private:
    CudaEnqueue(Simulation& simulation, cudaStream_t stream) : simulation_(simulation), stream_(stream) {}
    Simulation& simulation_;
    cudaStream_t stream_;
};
#endif

#ifdef HMSM_HAVE_VULKAN
/// hmsm::vulkan::record_steps into a command buffer the engine owns; the frame ends when its
/// submission's fence signals.
class VulkanRecord final : public FrameDriver {
public:
    static std::unique_ptr<FrameDriver> create(Simulation& simulation) {
        if (simulation.backend_kind() != BackendKind::vulkan) return nullptr;
        auto handles = hmsm::vulkan::device_handles(simulation);
        if (!handles) return nullptr;
        std::unique_ptr<VulkanRecord> driver(new VulkanRecord(*handles));
        return driver->ready() ? std::move(driver) : nullptr;
    }
    ~VulkanRecord() override {
        if (fence_) destroy_fence_(h_.device, fence_, nullptr);
        if (pool_) destroy_pool_(h_.device, pool_, nullptr);
        if (library_) dlclose(library_);
    }
    const char* path() const override { return "record"; }
    Status call(Simulation& simulation) override {
        VkCommandBufferBeginInfo begin{};
        begin.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO;
        begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
        if (reset_buffer_(buffer_, 0) != VK_SUCCESS || begin_(buffer_, &begin) != VK_SUCCESS)
            return {ErrorCode::device_error, "vulkan: cannot begin the frame's command buffer"};
        HMSM_TRY(hmsm::vulkan::record_steps(simulation, buffer_, 1));
        if (end_(buffer_) != VK_SUCCESS) return {ErrorCode::device_error, "vulkan: cannot end the command buffer"};
        return {};
    }
    Status finish(Simulation&) override {
        VkSubmitInfo submit{};
        submit.sType = VK_STRUCTURE_TYPE_SUBMIT_INFO;
        submit.commandBufferCount = 1;
        submit.pCommandBuffers = &buffer_;
        if (submit_(h_.queue, 1, &submit, fence_) != VK_SUCCESS ||
            wait_(h_.device, 1, &fence_, VK_TRUE, UINT64_MAX) != VK_SUCCESS || reset_fence_(h_.device, 1, &fence_) != VK_SUCCESS)
            return {ErrorCode::device_error, "vulkan: the frame's submission failed"};
        return {};
    }

private:
    explicit VulkanRecord(const hmsm::vulkan::DeviceHandles& handles) : h_(handles) {
        library_ = dlopen("libvulkan.so.1", RTLD_NOW | RTLD_LOCAL);
        if (!library_) return;
        auto device_proc = reinterpret_cast<PFN_vkGetDeviceProcAddr>(dlsym(library_, "vkGetDeviceProcAddr"));
        if (!device_proc) return;
        auto load = [&](auto& fn, const char* name) { fn = reinterpret_cast<std::decay_t<decltype(fn)>>(device_proc(h_.device, name)); };
        PFN_vkCreateCommandPool create_pool = nullptr;
        PFN_vkAllocateCommandBuffers allocate = nullptr;
        PFN_vkCreateFence create_fence = nullptr;
        load(create_pool, "vkCreateCommandPool");
        load(allocate, "vkAllocateCommandBuffers");
        load(create_fence, "vkCreateFence");
        load(destroy_pool_, "vkDestroyCommandPool");
        load(destroy_fence_, "vkDestroyFence");
        load(reset_buffer_, "vkResetCommandBuffer");
        load(begin_, "vkBeginCommandBuffer");
        load(end_, "vkEndCommandBuffer");
        load(submit_, "vkQueueSubmit");
        load(wait_, "vkWaitForFences");
        load(reset_fence_, "vkResetFences");
        if (!create_pool || !allocate || !create_fence || !destroy_pool_ || !destroy_fence_ || !reset_buffer_ ||
            !begin_ || !end_ || !submit_ || !wait_ || !reset_fence_)
            return;
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
        VkFenceCreateInfo fence{};
        fence.sType = VK_STRUCTURE_TYPE_FENCE_CREATE_INFO;
        if (create_fence(h_.device, &fence, nullptr, &fence_) != VK_SUCCESS) fence_ = VK_NULL_HANDLE;
    }
    bool ready() const { return fence_ != VK_NULL_HANDLE && buffer_ != VK_NULL_HANDLE; }

    hmsm::vulkan::DeviceHandles h_;
    void* library_ = nullptr;
    VkCommandPool pool_ = VK_NULL_HANDLE;
    VkCommandBuffer buffer_ = VK_NULL_HANDLE;
    VkFence fence_ = VK_NULL_HANDLE;
    PFN_vkDestroyCommandPool destroy_pool_ = nullptr;
    PFN_vkDestroyFence destroy_fence_ = nullptr;
    PFN_vkResetCommandBuffer reset_buffer_ = nullptr;
    PFN_vkBeginCommandBuffer begin_ = nullptr;
    PFN_vkEndCommandBuffer end_ = nullptr;
    PFN_vkQueueSubmit submit_ = nullptr;
    PFN_vkWaitForFences wait_ = nullptr;
    PFN_vkResetFences reset_fence_ = nullptr;
};
#endif

}  // namespace

std::vector<std::unique_ptr<FrameDriver>> engine_drivers(Simulation& simulation) {
    std::vector<std::unique_ptr<FrameDriver>> drivers;
    (void)simulation;
#ifdef HMSM_BENCH_CUDA_STREAM
    if (auto driver = CudaEnqueue::create(simulation)) drivers.push_back(std::move(driver));
#endif
#ifdef HMSM_HAVE_VULKAN
    if (auto driver = VulkanRecord::create(simulation)) drivers.push_back(std::move(driver));
#endif
    return drivers;
}

}  // namespace hmsm::cli::bench
