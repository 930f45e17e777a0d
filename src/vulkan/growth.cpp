// Growing a scene's buffers on the device (Backend::grow, capacity_growth.h): the buffers the
// capacities size are created anew and take their live elements with vkCmdCopyBuffer (both
// halves of a ping-pong buffer, the second at its new place), the rest zeroed with
// vkCmdFillBuffer, in one submission; model buffers and the wind table stay. A scene bound in
// windows lays its ping-pong buffers out per segment (windows.h): it does not grow here, nor
// does one that would need windows after the growth; the simulation uploads those anew.
#include "vulkan_backend.h"

#include "vk_error.h"

#include "../capacity_growth.h"
#include "../device_words.h"

#include <utility>
#include <vector>

namespace hmsm::detail::vk {

Status VulkanBackend::grow(const SceneData& scene) {
    HMSM_TRY(check_device_lost());
    if (!plan_ || !sets_) return {ErrorCode::internal, "vulkan: grow() before upload()"};
    if (plan_->split()) return {ErrorCode::unsupported, "vulkan: a scene bound in windows does not grow on the device"};
    // Changes held back name the buffers and the halves' places as they are now.
    HMSM_TRY(submit_held_back());
    // The copies need the logical layout on both sides: every buffer with elements as large as
    // its element count, the second half of a ping-pong buffer at the capacity (a plan of one
    // segment cut from a scene that does not fit a window lays its halves out per segment).
    auto logical_layout = [&](const WindowPlan& plan, const SceneData& d) {
        if (plan.split()) return false;
        for (const BufferInfo& info : kBufferTable)
            if (sized_by_capacity(info.id) && d.element_count(info.id) > 0 &&
                plan.physical_elements(info.id, d) != d.element_count(info.id))
                return false;
        return true;
    };
    for (const BufferInfo& info : kBufferTable) {
        const uint64_t count = element_counts_[uint32_t(info.id)];
        if (sized_by_capacity(info.id) && count > 0 &&
            buffers_[uint32_t(info.id)].size() != count * device_element_bytes(info.id))
            return {ErrorCode::unsupported, "vulkan: the scene's buffers are laid out per window: it is uploaded anew"};
    }
    std::unique_ptr<WindowPlan> kept_plan = std::move(plan_);
    Status planned = plan_windows(scene);
    if (planned.ok() && !logical_layout(*plan_, scene))
        planned = {ErrorCode::unsupported, "vulkan: the grown scene needs windows: it is uploaded anew"};
    if (planned.ok() && fault_ == VulkanFault::out_of_device_memory_at_growth)
        planned = failure(VK_ERROR_OUT_OF_DEVICE_MEMORY, "vkAllocateMemory (injected)", __FILE__, __LINE__);
    std::array<Buffer, kBufferCount> grown;
    std::array<GrowthPlan, kBufferCount> plans;
    for (const BufferInfo& info : kBufferTable) {
        if (!planned.ok()) break;
        const uint32_t b = uint32_t(info.id);
        const uint64_t count = scene.element_count(info.id);
        plans[b] = growth_plan(info.id, element_counts_[b], count, live_elements(scene, info.id));
        if (!plans[b].reallocates) continue;
        if (count < element_counts_[b]) {
            planned = {ErrorCode::internal, "vulkan: grow() would shrink buffer " + std::string(info.name)};
            break;
        }
        auto buffer = Buffer::create(*device_, plan_->physical_elements(info.id, scene) * device_element_bytes(info.id),
                                     usage_of(info.id), MemoryUse::device_local, std::string(info.name));
        if (!buffer) planned = buffer.status();
        else grown[b] = std::move(buffer).value();
    }
    // The copies read the old buffers only: until the new ones are taken, nothing has changed.
    if (planned.ok())
        planned = transfer_->submit([&](VkCommandBuffer cmd) {
            const VolkDeviceTable& vk = device_->vk();
            std::vector<VkBufferCopy> regions;
            for (const BufferInfo& info : kBufferTable) {
                const uint32_t b = uint32_t(info.id);
                const uint64_t element_bytes = device_element_bytes(info.id);
                regions.clear();
                for (const GrowthCopy& c : plans[b].copies)
                    regions.push_back({c.src * element_bytes, c.dst * element_bytes, c.count * element_bytes});
                if (!regions.empty())
                    vk.vkCmdCopyBuffer(cmd, buffers_[b].handle(), grown[b].handle(), uint32_t(regions.size()),
                                       regions.data());
                for (const GrowthZero& z : plans[b].zeros)
                    vk.vkCmdFillBuffer(cmd, grown[b].handle(), z.first * element_bytes, z.count * element_bytes, 0);
            }
        });
    std::array<uint64_t, kBufferCount> counts = element_counts_;
    if (planned.ok()) {
        for (const BufferInfo& info : kBufferTable) {
            const uint32_t b = uint32_t(info.id);
            if (!plans[b].reallocates) continue;
            std::swap(buffers_[b], grown[b]);  // `grown` holds the old buffers from here on
            element_counts_[b] = scene.element_count(info.id);
        }
        auto sets = WindowSets::create(*device_, pipelines_->set_layout(), *plan_, buffers_);
        if (sets) {
            recording_.clear();  // its descriptor sets go
            one_off_recording_.clear();
            sets_ = std::move(sets).value();
            return device_->take_validation_messages();
        }
        planned = sets.status();
        for (const BufferInfo& info : kBufferTable)
            if (plans[uint32_t(info.id)].reallocates) std::swap(buffers_[uint32_t(info.id)], grown[uint32_t(info.id)]);
        element_counts_ = counts;
    }
    plan_ = std::move(kept_plan);
    return planned;
}

}  // namespace hmsm::detail::vk
