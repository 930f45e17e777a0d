#include "device_buffer.h"

#include "vk_error.h"

#include <algorithm>
#include <vector>

namespace hmsm::detail::vk {
namespace {

/// Staging chunks are at most this large: big enough to stream at full speed, small enough not
/// to double the memory of a large scene.
constexpr VkDeviceSize kMaxStagingBytes = VkDeviceSize(64) << 20;

/// The first memory type allowed by `type_bits` with all `required` flags, preferring one that
/// also has `preferred`; -1 when none.
int find_memory_type(const VkPhysicalDeviceMemoryProperties& memory, uint32_t type_bits,
                     VkMemoryPropertyFlags required, VkMemoryPropertyFlags preferred) {
    int fallback = -1;
    for (uint32_t i = 0; i < memory.memoryTypeCount; ++i) {
        if (!(type_bits & (1u << i))) continue;
        VkMemoryPropertyFlags flags = memory.memoryTypes[i].propertyFlags;
        if ((flags & required) != required) continue;
        if ((flags & preferred) == preferred) return int(i);
        if (fallback < 0) fallback = int(i);
    }
    return fallback;
}

}  // namespace

Buffer& Buffer::operator=(Buffer&& other) noexcept {
    if (this != &other) {
        reset();
        device_ = std::exchange(other.device_, nullptr);
        buffer_ = std::exchange(other.buffer_, VK_NULL_HANDLE);
        memory_ = std::exchange(other.memory_, VK_NULL_HANDLE);
        size_ = std::exchange(other.size_, 0);
        mapped_ = std::exchange(other.mapped_, nullptr);
    }
    return *this;
}

void Buffer::reset() {
    if (!device_) return;
    const VolkDeviceTable& vk = device_->vk();
    if (buffer_) vk.vkDestroyBuffer(device_->handle(), buffer_, nullptr);
    if (memory_) vk.vkFreeMemory(device_->handle(), memory_, nullptr);  // also unmaps
    device_ = nullptr;
    buffer_ = VK_NULL_HANDLE;
    memory_ = VK_NULL_HANDLE;
    mapped_ = nullptr;
    size_ = 0;
}

Result<Buffer> Buffer::create(const Device& device, VkDeviceSize size, VkBufferUsageFlags usage,
                              MemoryUse use, const std::string& name) {
    const VolkDeviceTable& vk = device.vk();
    Buffer b;
    b.device_ = &device;
    b.size_ = size;
    VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    info.size = std::max<VkDeviceSize>(size, 16);  // zero-sized buffers are invalid
    info.usage = usage;
    info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    if (VkResult r = vk.vkCreateBuffer(device.handle(), &info, nullptr, &b.buffer_); r != VK_SUCCESS) {
        Status failed = failure(r, "vkCreateBuffer", __FILE__, __LINE__);
        return Status{failed.code(), "vulkan: cannot create buffer " + name + " of " + std::to_string(size) +
                                         " bytes on " + device.name() + ": " + result_name(r)};
    }

    VkMemoryRequirements requirements;
    vk.vkGetBufferMemoryRequirements(device.handle(), b.buffer_, &requirements);
    const VkMemoryPropertyFlags required =
        use == MemoryUse::staging
            ? VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT
            : VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT;
    const VkMemoryPropertyFlags preferred =
        use == MemoryUse::staging ? required | VK_MEMORY_PROPERTY_HOST_CACHED_BIT : required;
    int type = find_memory_type(device.memory_properties(), requirements.memoryTypeBits, required,
                                preferred);
    if (type < 0)
        return Status{ErrorCode::unsupported,
                      "vulkan: no suitable memory type for buffer " + name + " on " + device.name()};
    // maxMemoryAllocationSize is a soft limit ("may" fail with VK_ERROR_OUT_OF_DEVICE_MEMORY;
    // NVIDIA reports 4 GiB and allocates more): a buffer beyond it is tried, and a failure names
    // the limit. One beyond its heap cannot succeed and is refused before allocating.
    const DeviceLimits& limits = device.limits();
    const VkMemoryHeap& heap =
        device.memory_properties().memoryHeaps[device.memory_properties().memoryTypes[type].heapIndex];
    const bool above_soft_limit =
        limits.max_memory_allocation_size && requirements.size > limits.max_memory_allocation_size;
    if (requirements.size > heap.size)
        return Status{ErrorCode::out_of_memory,
                      "vulkan: buffer " + name + " needs " + std::to_string(requirements.size) +
                          " bytes, more than its memory heap (" + std::to_string(heap.size) +
                          " bytes) of " + device.name()};

    VkMemoryAllocateInfo allocate{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    allocate.allocationSize = requirements.size;
    allocate.memoryTypeIndex = uint32_t(type);
    if (VkResult r = vk.vkAllocateMemory(device.handle(), &allocate, nullptr, &b.memory_); r != VK_SUCCESS) {
        Status failed = failure(r, "vkAllocateMemory", __FILE__, __LINE__);
        return Status{failed.code(),
                      "vulkan: cannot allocate " + std::to_string(requirements.size) + " bytes for buffer " +
                          name + " on " + device.name() + ": " + result_name(r) +
                          (above_soft_limit ? " (more than maxMemoryAllocationSize, " +
                                                  std::to_string(limits.max_memory_allocation_size) +
                                                  " bytes; use fewer instances per simulation)"
                                            : std::string())};
    }
    HMSM_VK_TRY(vk.vkBindBufferMemory(device.handle(), b.buffer_, b.memory_, 0));
    if (use == MemoryUse::staging)
        HMSM_VK_TRY(vk.vkMapMemory(device.handle(), b.memory_, 0, VK_WHOLE_SIZE, 0, &b.mapped_));
    return b;
}

void barrier_after_all_writes(const Device& device, VkCommandBuffer cmd, VkPipelineStageFlags dst_stage,
                              VkAccessFlags dst_access) {
    VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    barrier.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
    barrier.dstAccessMask = dst_access;
    device.vk().vkCmdPipelineBarrier(
        cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT, dst_stage, 0, 1,
        &barrier, 0, nullptr, 0, nullptr);
}

Result<std::unique_ptr<Transfer>> Transfer::create(const Device& device) {
    std::unique_ptr<Transfer> t(new Transfer(device));
    const VolkDeviceTable& vk = device.vk();
    VkCommandPoolCreateInfo pool{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pool.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT | VK_COMMAND_POOL_CREATE_TRANSIENT_BIT;
    pool.queueFamilyIndex = device.queue_family();
    HMSM_VK_TRY(vk.vkCreateCommandPool(device.handle(), &pool, nullptr, &t->pool_));
    VkCommandBufferAllocateInfo allocate{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    allocate.commandPool = t->pool_;
    allocate.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    allocate.commandBufferCount = 1;
    HMSM_VK_TRY(vk.vkAllocateCommandBuffers(device.handle(), &allocate, &t->command_buffer_));
    VkFenceCreateInfo fence{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    HMSM_VK_TRY(vk.vkCreateFence(device.handle(), &fence, nullptr, &t->fence_));
    return t;
}

Transfer::~Transfer() {
    const VolkDeviceTable& vk = device_.vk();
    if (fence_) vk.vkDestroyFence(device_.handle(), fence_, nullptr);
    if (pool_) vk.vkDestroyCommandPool(device_.handle(), pool_, nullptr);
}

Status Transfer::ensure_staging(VkDeviceSize bytes) {
    VkDeviceSize wanted = std::clamp<VkDeviceSize>(bytes, 64 << 10, kMaxStagingBytes);
    if (staging_.handle() && staging_.size() >= wanted) return {};
    auto staging = Buffer::create(device_, wanted,
                                  VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                                  MemoryUse::staging, "staging");
    if (!staging) return staging.status();
    staging_ = std::move(staging).value();
    return {};
}

Status Transfer::submit(const std::function<void(VkCommandBuffer)>& commands) {
    const VolkDeviceTable& vk = device_.vk();
    HMSM_VK_TRY(vk.vkResetCommandBuffer(command_buffer_, 0));
    VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    HMSM_VK_TRY(vk.vkBeginCommandBuffer(command_buffer_, &begin));
    barrier_after_all_writes(device_, command_buffer_, VK_PIPELINE_STAGE_TRANSFER_BIT,
                             VK_ACCESS_TRANSFER_READ_BIT | VK_ACCESS_TRANSFER_WRITE_BIT);
    commands(command_buffer_);
    // Copies into the staging buffer become visible to the host once the fence signals.
    VkMemoryBarrier to_host{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    to_host.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    to_host.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
    vk.vkCmdPipelineBarrier(command_buffer_, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT,
                            0, 1, &to_host, 0, nullptr, 0, nullptr);
    HMSM_VK_TRY(vk.vkEndCommandBuffer(command_buffer_));
    VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    submit.commandBufferCount = 1;
    submit.pCommandBuffers = &command_buffer_;
    HMSM_VK_TRY(vk.vkResetFences(device_.handle(), 1, &fence_));
    HMSM_VK_TRY(device_.submit(submit, fence_));
    ++submissions_;
    HMSM_VK_TRY(vk.vkWaitForFences(device_.handle(), 1, &fence_, VK_TRUE, UINT64_MAX));
    return {};
}

Status Transfer::upload(const Buffer& dst, VkDeviceSize offset, VkDeviceSize bytes,
                        const std::function<void(void*, VkDeviceSize, VkDeviceSize)>& fill) {
    HMSM_TRY(ensure_staging(bytes));
    for (VkDeviceSize done = 0; done < bytes;) {
        VkDeviceSize chunk = std::min(bytes - done, staging_.size());
        fill(staging_.mapped(), done, chunk);
        VkBufferCopy region{0, offset + done, chunk};
        HMSM_TRY(submit([&](VkCommandBuffer cmd) {
            device_.vk().vkCmdCopyBuffer(cmd, staging_.handle(), dst.handle(), 1, &region);
        }));
        done += chunk;
    }
    return {};
}

Status Transfer::upload_then(const Buffer& dst, VkDeviceSize offset, VkDeviceSize bytes,
                             const std::function<void(void*, VkDeviceSize, VkDeviceSize)>& fill,
                             const std::function<Status(VkCommandBuffer)>& then) {
    if (bytes > most_staged_bytes())
        return {ErrorCode::internal, "vulkan: upload_then of " + std::to_string(bytes) + " bytes, past the staging"};
    HMSM_TRY(ensure_staging(bytes));
    if (bytes > 0) fill(staging_.mapped(), 0, bytes);
    Status recorded;
    HMSM_TRY(submit([&](VkCommandBuffer cmd) {
        if (bytes > 0) {
            const VkBufferCopy region{0, offset, bytes};
            device_.vk().vkCmdCopyBuffer(cmd, staging_.handle(), dst.handle(), 1, &region);
        }
        barrier_after_all_writes(device_, cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                                 VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT |
                                     VK_ACCESS_TRANSFER_READ_BIT | VK_ACCESS_TRANSFER_WRITE_BIT);
        recorded = then(cmd);
        // What `then` wrote, before whatever later submissions read or write.
        barrier_after_all_writes(device_, cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                                 VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT |
                                     VK_ACCESS_TRANSFER_READ_BIT | VK_ACCESS_TRANSFER_WRITE_BIT);
    }));
    return recorded;
}

Status Transfer::download(const Buffer& src, VkDeviceSize offset, VkDeviceSize bytes,
                          const std::function<void(const void*, VkDeviceSize, VkDeviceSize)>& consume) {
    HMSM_TRY(ensure_staging(bytes));
    for (VkDeviceSize done = 0; done < bytes;) {
        VkDeviceSize chunk = std::min(bytes - done, staging_.size());
        VkBufferCopy region{offset + done, 0, chunk};
        HMSM_TRY(submit([&](VkCommandBuffer cmd) {
            device_.vk().vkCmdCopyBuffer(cmd, src.handle(), staging_.handle(), 1, &region);
        }));
        consume(staging_.mapped(), done, chunk);
        done += chunk;
    }
    return {};
}

namespace {

/// The copies of one staging-full of packed regions: bytes [first, first + bytes) of the
/// regions back to back, as copies between the device buffer (srcOffset: its offset) and the
/// staging buffer (dstOffset: the offset in staging).
struct StagedChunk {
    VkDeviceSize first = 0, bytes = 0;
    std::vector<VkBufferCopy> copies;
};

/// `regions` (size: the bytes, srcOffset: the device offset) cut into staging-fulls of at most
/// `staging` bytes; a region crossing a chunk's end goes on in the next.
std::vector<StagedChunk> staged_chunks(std::span<const VkBufferCopy> regions, VkDeviceSize staging) {
    std::vector<StagedChunk> chunks;
    VkDeviceSize packed = 0;
    for (const VkBufferCopy& r : regions) {
        for (VkDeviceSize done = 0; done < r.size;) {
            if (chunks.empty() || chunks.back().bytes == staging) chunks.push_back({packed, 0, {}});
            StagedChunk& chunk = chunks.back();
            const VkDeviceSize n = std::min(r.size - done, staging - chunk.bytes);
            chunk.copies.push_back({r.srcOffset + done, chunk.bytes, n});
            chunk.bytes += n;
            done += n;
            packed += n;
        }
    }
    return chunks;
}

VkDeviceSize total_bytes(std::span<const VkBufferCopy> regions) {
    VkDeviceSize total = 0;
    for (const VkBufferCopy& r : regions) total += r.size;
    return total;
}

}  // namespace

Status Transfer::download_ranges(const Buffer& src, std::span<const VkBufferCopy> regions,
                                 const std::function<void(const void*, VkDeviceSize, VkDeviceSize)>& consume) {
    const VkDeviceSize total = total_bytes(regions);
    if (total == 0) return {};
    HMSM_TRY(ensure_staging(total));
    for (const StagedChunk& chunk : staged_chunks(regions, staging_.size())) {
        HMSM_TRY(submit([&](VkCommandBuffer cmd) {
            device_.vk().vkCmdCopyBuffer(cmd, src.handle(), staging_.handle(), uint32_t(chunk.copies.size()),
                                         chunk.copies.data());
        }));
        consume(staging_.mapped(), chunk.first, chunk.bytes);
    }
    return {};
}

Status Transfer::upload_ranges(const Buffer& dst, std::span<const VkBufferCopy> regions,
                               const std::function<void(void*, VkDeviceSize, VkDeviceSize)>& fill) {
    const VkDeviceSize total = total_bytes(regions);
    if (total == 0) return {};
    HMSM_TRY(ensure_staging(total));
    for (const StagedChunk& chunk : staged_chunks(regions, staging_.size())) {
        fill(staging_.mapped(), chunk.first, chunk.bytes);
        std::vector<VkBufferCopy> back(chunk.copies.size());
        for (size_t k = 0; k < back.size(); ++k)
            back[k] = {chunk.copies[k].dstOffset, chunk.copies[k].srcOffset, chunk.copies[k].size};
        HMSM_TRY(submit([&](VkCommandBuffer cmd) {
            device_.vk().vkCmdCopyBuffer(cmd, staging_.handle(), dst.handle(), uint32_t(back.size()), back.data());
        }));
    }
    return {};
}

VkDeviceSize Transfer::most_staged_bytes() { return kMaxStagingBytes; }

namespace {

/// The staging copies of `parts`, back to back: per part the copies (srcOffset in the buffer,
/// dstOffset in staging), and where each part starts in staging.
struct PackedParts {
    std::vector<std::vector<VkBufferCopy>> copies;
    std::vector<VkDeviceSize> first;
    VkDeviceSize bytes = 0;
};

PackedParts pack_parts(std::span<const Transfer::BufferRegions> parts) {
    PackedParts packed;
    for (const Transfer::BufferRegions& part : parts) {
        packed.first.push_back(packed.bytes);
        std::vector<VkBufferCopy>& copies = packed.copies.emplace_back();
        for (const VkBufferCopy& r : part.regions) {
            if (r.size == 0) continue;
            copies.push_back({r.srcOffset, packed.bytes, r.size});
            packed.bytes += r.size;
        }
    }
    return packed;
}

}  // namespace

Status Transfer::download_parts(std::span<const BufferRegions> parts,
                                const std::function<void(size_t, const void*)>& consume) {
    const PackedParts packed = pack_parts(parts);
    if (packed.bytes > kMaxStagingBytes)
        return {ErrorCode::internal, "vulkan: download_parts of more than the staging buffer"};
    if (packed.bytes == 0) return {};
    HMSM_TRY(ensure_staging(packed.bytes));
    HMSM_TRY(submit([&](VkCommandBuffer cmd) {
        for (size_t k = 0; k < parts.size(); ++k)
            if (!packed.copies[k].empty())
                device_.vk().vkCmdCopyBuffer(cmd, parts[k].buffer->handle(), staging_.handle(),
                                             uint32_t(packed.copies[k].size()), packed.copies[k].data());
    }));
    for (size_t k = 0; k < parts.size(); ++k)
        consume(k, static_cast<const std::byte*>(staging_.mapped()) + packed.first[k]);
    return {};
}

Status Transfer::upload_parts(std::span<const BufferRegions> parts, const std::function<void(size_t, void*)>& fill) {
    const PackedParts packed = pack_parts(parts);
    if (packed.bytes > kMaxStagingBytes)
        return {ErrorCode::internal, "vulkan: upload_parts of more than the staging buffer"};
    if (packed.bytes == 0) return {};
    HMSM_TRY(ensure_staging(packed.bytes));
    for (size_t k = 0; k < parts.size(); ++k) fill(k, static_cast<std::byte*>(staging_.mapped()) + packed.first[k]);
    return submit([&](VkCommandBuffer cmd) {
        for (size_t k = 0; k < parts.size(); ++k) {
            std::vector<VkBufferCopy> back;
            back.reserve(packed.copies[k].size());
            for (const VkBufferCopy& c : packed.copies[k]) back.push_back({c.dstOffset, c.srcOffset, c.size});
            if (!back.empty())
                device_.vk().vkCmdCopyBuffer(cmd, staging_.handle(), parts[k].buffer->handle(), uint32_t(back.size()),
                                             back.data());
        }
    });
}

}  // namespace hmsm::detail::vk
