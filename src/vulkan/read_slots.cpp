#include "read_slots.h"

#include "vk_error.h"
#include "vulkan_backend.h"

#include "../device_words.h"

#include <algorithm>
#include <atomic>
#include <string>
#include <vector>

namespace hmsm::detail {
namespace {
std::atomic<uint64_t> g_read_slot_bytes{0};
}  // namespace

void vulkan_set_read_slot_bytes(uint64_t bytes) { g_read_slot_bytes = bytes; }
}  // namespace hmsm::detail

namespace hmsm::detail::vk {

Result<std::unique_ptr<ReadSlots>> ReadSlots::create(const Device& device) {
    std::unique_ptr<ReadSlots> slots(new ReadSlots(device));
    VkCommandPoolCreateInfo pool{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pool.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    pool.queueFamilyIndex = device.queue_family();
    HMSM_VK_TRY(device.vk().vkCreateCommandPool(device.handle(), &pool, nullptr, &slots->pool_));
    return slots;
}

ReadSlots::~ReadSlots() {
    const VolkDeviceTable& vk = device_.vk();
    for (Slot& slot : slots_) {
        if (slot.pending) vk.vkWaitForFences(device_.handle(), 1, &slot.fence, VK_TRUE, UINT64_MAX);
        if (slot.fence) vk.vkDestroyFence(device_.handle(), slot.fence, nullptr);
    }
    if (pool_) vk.vkDestroyCommandPool(device_.handle(), pool_, nullptr);  // frees the command buffers
}

bool ReadSlots::fits(VkDeviceSize bytes) const {
    const VkDeviceSize most = device_.limits().max_memory_allocation_size;
    const uint64_t hook = g_read_slot_bytes.load();
    return (most == 0 || bytes <= most) && (hook == 0 || bytes <= hook);
}

Status ReadSlots::wait(Slot& slot) {
    if (!slot.pending) return {};
    slot.pending = false;
    HMSM_VK_TRY(device_.vk().vkWaitForFences(device_.handle(), 1, &slot.fence, VK_TRUE, UINT64_MAX));
    return {};
}

Status ReadSlots::request(uint32_t slot_index, VkBuffer src, std::span<const VkBufferCopy> regions,
                          VkDeviceSize bytes) {
    const VolkDeviceTable& vk = device_.vk();
    Slot& slot = slots_[slot_index];
    HMSM_TRY(wait(slot));
    if (slot.buffer.size() < bytes) {
        // Half as large again as asked, so that a growing scene reallocates a few times only.
        const VkDeviceSize most = device_.limits().max_memory_allocation_size;
        VkDeviceSize size = std::max(bytes, slot.buffer.size() + slot.buffer.size() / 2);
        if (most) size = std::min(size, most);
        slot.buffer = Buffer();
        auto grown = Buffer::create(device_, size, VK_BUFFER_USAGE_TRANSFER_DST_BIT, MemoryUse::staging,
                                    "read slot " + std::to_string(slot_index));
        if (!grown) return grown.status();
        slot.buffer = std::move(grown).value();
    }
    if (!slot.command_buffer) {
        VkCommandBufferAllocateInfo allocate{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
        allocate.commandPool = pool_;
        allocate.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
        allocate.commandBufferCount = 1;
        HMSM_VK_TRY(vk.vkAllocateCommandBuffers(device_.handle(), &allocate, &slot.command_buffer));
        VkFenceCreateInfo fence{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
        HMSM_VK_TRY(vk.vkCreateFence(device_.handle(), &fence, nullptr, &slot.fence));
    }
    HMSM_VK_TRY(vk.vkResetCommandBuffer(slot.command_buffer, 0));
    VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    HMSM_VK_TRY(vk.vkBeginCommandBuffer(slot.command_buffer, &begin));
    barrier_after_all_writes(device_, slot.command_buffer, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_READ_BIT);
    if (!regions.empty())
        vk.vkCmdCopyBuffer(slot.command_buffer, src, slot.buffer.handle(), uint32_t(regions.size()), regions.data());
    VkMemoryBarrier to_host{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    to_host.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    to_host.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
    vk.vkCmdPipelineBarrier(slot.command_buffer, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1,
                            &to_host, 0, nullptr, 0, nullptr);
    HMSM_VK_TRY(vk.vkEndCommandBuffer(slot.command_buffer));
    VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    submit.commandBufferCount = 1;
    submit.pCommandBuffers = &slot.command_buffer;
    HMSM_VK_TRY(vk.vkResetFences(device_.handle(), 1, &slot.fence));
    HMSM_VK_TRY(device_.submit(submit, slot.fence));
    ++submissions_;
    slot.pending = true;
    return {};
}

Result<const void*> ReadSlots::take(uint32_t slot_index) {
    Slot& slot = slots_[slot_index];
    HMSM_TRY(wait(slot));
    return static_cast<const void*>(slot.buffer.mapped());
}

// The backend's side (Backend::request_read / take_read).

Status VulkanBackend::request_read(uint32_t slot, BufferId id, uint64_t first, uint64_t count) const {
    HMSM_TRY(check_device_lost());
    HMSM_TRY(check_range(id, first, count));
    if (slot >= kReadSlots || shape_is_integer(buffer_info(id).shape))
        return {ErrorCode::internal, "vulkan: read slot " + std::to_string(slot) + " of buffer " +
                                         std::string(buffer_info(id).name) + " is not an output read"};
    // A read sees every change made before it (read()).
    HMSM_TRY(const_cast<VulkanBackend*>(this)->submit_held_back());
    const uint64_t element_bytes = device_element_bytes(id);
    std::vector<float>& host = read_fallback_[slot];
    if (count == 0 || !read_slots_->fits(count * element_bytes)) {
        // Past one allocation of the device: through the staging chunks into host memory
        // (nothing to copy for no elements).
        host.resize(count * element_bytes / 4);
        read_from_host_[slot] = true;
        return count == 0 ? Status{} : read(id, first, count, host.data(), Scalar::f32);
    }
    read_from_host_[slot] = false;
    host = {};
    // Pieces: one unless a ping-pong buffer of a split scene is read across segments.
    std::vector<VkBufferCopy> regions;
    for (const WindowPlan::Piece& piece : plan_->pieces(id, first, count))
        regions.push_back({piece.physical * element_bytes, (piece.logical - first) * element_bytes,
                           piece.count * element_bytes});
    HMSM_TRY(read_slots_->request(slot, buffers_[uint32_t(id)].handle(), regions, count * element_bytes));
    return device_->take_validation_messages();
}

Result<const float*> VulkanBackend::take_read(uint32_t slot) const {
    HMSM_TRY(check_device_lost());
    if (slot >= kReadSlots) return Status{ErrorCode::internal, "vulkan: no read slot " + std::to_string(slot)};
    if (read_from_host_[slot]) return static_cast<const float*>(read_fallback_[slot].data());
    auto taken = read_slots_->take(slot);
    if (!taken) return taken.status();
    HMSM_TRY(device_->take_validation_messages());
    return static_cast<const float*>(*taken);
}

}  // namespace hmsm::detail::vk
