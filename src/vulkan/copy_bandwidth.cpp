// The device-memory roofline of `hmsm bench` on Vulkan: a copy between two DEVICE_LOCAL
// buffers timed with GPU timestamps, counted as (bytes read + bytes written) / device seconds,
// the method of CUDA's cudaMemcpyDeviceToDevice measurement (src/cuda/cuda_backend.cpp).
//
// Two copies are timed and the faster one is the roofline. vkCmdCopyBuffer alone is not
// enough: on an H100 the hmsm passes themselves (SM loads and stores) outran that "roofline"
// (measured: docs/benchmarks/README.md, copy bandwidth) — the driver
// apparently serves it with a copy (DMA) engine rather than the SMs. The second copy is a
// compute shader (shaders/glsl/copy_bandwidth.comp) streaming 16-byte words like the passes.
#include "vulkan_backend.h"

#include "pipelines.h"
#include "vk_error.h"

#include "hmsm_spirv/copy_bandwidth.h"

#include <algorithm>
#include <functional>
#include <vector>

namespace hmsm::detail::vk {
namespace {

constexpr uint32_t kCopyWorkgroupSize = 256;  // local_size_x of copy_bandwidth.comp

/// The compute pipeline of copy_bandwidth.comp bound to two buffers; destroys what it made.
class ShaderCopy {
public:
    explicit ShaderCopy(const Device& device) : device_(device) {}
    ~ShaderCopy() {
        const VolkDeviceTable& vk = device_.vk();
        VkDevice dev = device_.handle();
        if (pipeline_) vk.vkDestroyPipeline(dev, pipeline_, nullptr);
        if (layout_) vk.vkDestroyPipelineLayout(dev, layout_, nullptr);
        if (pool_) vk.vkDestroyDescriptorPool(dev, pool_, nullptr);  // frees set_
        if (set_layout_) vk.vkDestroyDescriptorSetLayout(dev, set_layout_, nullptr);
    }

    Status create(const Buffer& source, const Buffer& target, VkDeviceSize bytes) {
        const VolkDeviceTable& vk = device_.vk();
        VkDevice dev = device_.handle();
        HMSM_TRY(storage_buffer_set_layout(device_, 2, set_layout_));

        VkPushConstantRange push{VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(uint32_t)};
        VkPipelineLayoutCreateInfo layout_info{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
        layout_info.setLayoutCount = 1;
        layout_info.pSetLayouts = &set_layout_;
        layout_info.pushConstantRangeCount = 1;
        layout_info.pPushConstantRanges = &push;
        HMSM_VK_TRY(vk.vkCreatePipelineLayout(dev, &layout_info, nullptr, &layout_));

        auto pipeline = compute_pipeline(device_, layout_, hmsm_spirv_copy_bandwidth);
        if (!pipeline) return pipeline.status();
        pipeline_ = *pipeline;

        VkDescriptorPoolSize size{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 2};
        VkDescriptorPoolCreateInfo pool_info{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
        pool_info.maxSets = 1;
        pool_info.poolSizeCount = 1;
        pool_info.pPoolSizes = &size;
        HMSM_VK_TRY(vk.vkCreateDescriptorPool(dev, &pool_info, nullptr, &pool_));
        VkDescriptorSetAllocateInfo allocate{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
        allocate.descriptorPool = pool_;
        allocate.descriptorSetCount = 1;
        allocate.pSetLayouts = &set_layout_;
        HMSM_VK_TRY(vk.vkAllocateDescriptorSets(dev, &allocate, &set_));
        VkDescriptorBufferInfo buffers[2] = {{source.handle(), 0, bytes}, {target.handle(), 0, bytes}};
        VkWriteDescriptorSet write{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
        write.dstSet = set_;
        write.dstBinding = 0;
        write.descriptorCount = 2;
        write.descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
        write.pBufferInfo = buffers;
        vk.vkUpdateDescriptorSets(dev, 1, &write, 0, nullptr);
        words_ = uint32_t(bytes / 16);
        return {};
    }

    /// Records the copy; enough workgroups to fill any GPU, each looping over the words.
    void record(VkCommandBuffer cmd) const {
        const VolkDeviceTable& vk = device_.vk();
        vk.vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline_);
        vk.vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, layout_, 0, 1, &set_, 0, nullptr);
        vk.vkCmdPushConstants(cmd, layout_, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(uint32_t), &words_);
        const uint64_t needed = (uint64_t(words_) + kCopyWorkgroupSize - 1) / kCopyWorkgroupSize;
        const uint32_t groups = uint32_t(std::clamp<uint64_t>(
            needed, 1, std::min<uint64_t>(65535, device_.limits().max_workgroup_count[0])));
        vk.vkCmdDispatch(cmd, groups, 1, 1);
    }

private:
    const Device& device_;
    VkDescriptorSetLayout set_layout_ = VK_NULL_HANDLE;
    VkPipelineLayout layout_ = VK_NULL_HANDLE;
    VkPipeline pipeline_ = VK_NULL_HANDLE;
    VkDescriptorPool pool_ = VK_NULL_HANDLE;
    VkDescriptorSet set_ = VK_NULL_HANDLE;
    uint32_t words_ = 0;
};

/// Runs `copy` once to warm up, then five times between two timestamps, one submission each
/// (Transfer::submit orders it after all earlier writes); returns the median device seconds.
Result<double> median_seconds(const Device& device, Transfer& transfer, VkQueryPool pool,
                              const std::function<void(VkCommandBuffer)>& copy) {
    const VolkDeviceTable& vk = device.vk();
    const DeviceLimits& limits = device.limits();
    const uint64_t mask =
        limits.timestamp_valid_bits >= 64 ? ~uint64_t(0) : (uint64_t(1) << limits.timestamp_valid_bits) - 1;
    std::vector<double> seconds;
    for (int repeat = 0; repeat < 6; ++repeat) {
        HMSM_TRY(transfer.submit([&](VkCommandBuffer cmd) {
            // The shader copy reads and writes in the compute stage: order it after earlier
            // transfer and shader writes as Transfer::submit does for the transfer stage.
            barrier_after_all_writes(device, cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                                     VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT);
            vk.vkCmdResetQueryPool(cmd, pool, 0, 2);
            vk.vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, pool, 0);
            copy(cmd);
            vk.vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, pool, 1);
        }));
        uint64_t ticks[2] = {};
        if (vk.vkGetQueryPoolResults(device.handle(), pool, 0, 2, sizeof ticks, ticks, sizeof(uint64_t),
                                     VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT) != VK_SUCCESS)
            return Status{ErrorCode::device_error, "vulkan: timestamp query failed"};
        if (repeat > 0) seconds.push_back(double((ticks[1] - ticks[0]) & mask) * limits.timestamp_period_ns * 1e-9);
    }
    std::sort(seconds.begin(), seconds.end());
    return seconds[seconds.size() / 2];
}

}  // namespace

Result<double> VulkanBackend::measure_copy_bandwidth(uint64_t bytes) {
    const DeviceLimits& limits = device_->limits();
    if (limits.timestamp_period_ns <= 0.0)
        return Status{ErrorCode::unsupported, "vulkan: the compute queue has no timestamps"};
    // One storage-buffer binding covers the whole block, in whole 16-byte words.
    bytes = std::min<uint64_t>({bytes, limits.max_memory_allocation_size, limits.max_storage_buffer_range});
    bytes -= bytes % 16;
    if (bytes == 0) return Status{ErrorCode::invalid_argument, "vulkan: copy block of less than 16 bytes"};
    const VkBufferUsageFlags usage =
        VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT | VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
    auto source = Buffer::create(*device_, bytes, usage, MemoryUse::device_local, "copy bandwidth source");
    if (!source) return source.status();
    auto target = Buffer::create(*device_, bytes, usage, MemoryUse::device_local, "copy bandwidth target");
    if (!target) return target.status();
    ShaderCopy shader(*device_);
    HMSM_TRY(shader.create(*source, *target, bytes));
    const VolkDeviceTable& vk = device_->vk();
    HMSM_TRY(transfer_->submit(
        [&](VkCommandBuffer cmd) { vk.vkCmdFillBuffer(cmd, source->handle(), 0, bytes, 0x3c3c3c3cu); }));

    VkQueryPoolCreateInfo info{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
    info.queryType = VK_QUERY_TYPE_TIMESTAMP;
    info.queryCount = 2;
    VkQueryPool pool = VK_NULL_HANDLE;
    HMSM_VK_TRY(vk.vkCreateQueryPool(device_->handle(), &info, nullptr, &pool));
    Result<double> transfer_copy = median_seconds(*device_, *transfer_, pool, [&](VkCommandBuffer cmd) {
        VkBufferCopy region{0, 0, bytes};
        vk.vkCmdCopyBuffer(cmd, source->handle(), target->handle(), 1, &region);
    });
    Result<double> shader_copy = transfer_copy.ok()
                                     ? median_seconds(*device_, *transfer_, pool,
                                                      [&](VkCommandBuffer cmd) { shader.record(cmd); })
                                     : transfer_copy;
    vk.vkDestroyQueryPool(device_->handle(), pool, nullptr);
    if (!shader_copy) return shader_copy.status();
    HMSM_TRY(device_->take_validation_messages());
    const double seconds = std::min(*transfer_copy, *shader_copy);
    if (!(seconds > 0.0)) return Status{ErrorCode::device_error, "vulkan: copy took no measurable time"};
    return 2.0 * double(bytes) / seconds;
}

}  // namespace hmsm::detail::vk
