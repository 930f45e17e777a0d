// Backend::read_ranges and write_ranges of the Vulkan backend: every range of a call in one
// copy command (a region per range) to or from the transfer staging buffer, one submission
// and wait per staging-full. Inside an engine's recording or a held-back instance change the
// ranges go range by range the way write() goes (the ring, deferred_changes.cpp).
#include "vulkan_backend.h"

#include "../device_words.h"

#include <vector>

namespace hmsm::detail::vk {

bool VulkanBackend::copies_ranges_at_once(std::span<const ElementRange> ranges, bool writes) const {
    if (!batch_transfers_ || !plan_ || plan_->split()) return false;
    if (writes && (record_target_ || holding_back() || ranges_overlap(ranges))) return false;
    return true;
}

Status VulkanBackend::read_ranges(BufferId id, std::span<const ElementRange> ranges, void* dst, Scalar as) const {
    if (!copies_ranges_at_once(ranges, false)) return Backend::read_ranges(id, ranges, dst, as);
    HMSM_TRY(check_device_lost());
    for (const ElementRange& r : ranges) HMSM_TRY(check_range(id, r.first, r.count));
    // A read sees every change made before it (read()).
    HMSM_TRY(const_cast<VulkanBackend*>(this)->submit_held_back());
    const Shape shape = buffer_info(id).shape;
    const uint64_t element_bytes = device_element_bytes(id), scalar_bytes = as == Scalar::f64 ? 8 : 4;
    std::vector<VkBufferCopy> regions;
    regions.reserve(ranges.size());
    for (const ElementRange& r : ranges)
        if (r.count > 0) regions.push_back({r.first * element_bytes, 0, r.count * element_bytes});
    auto* out = static_cast<std::byte*>(dst);
    HMSM_TRY(transfer_->download_ranges(buffers_[uint32_t(id)], regions,
                                        [&](const void* staging, VkDeviceSize first_byte, VkDeviceSize bytes) {
                                            words_to_scalars(shape, staging, bytes / 4,
                                                             out + first_byte / 4 * scalar_bytes, as);
                                        }));
    return device_->take_validation_messages();
}

Status VulkanBackend::write_ranges(BufferId id, std::span<const ElementRange> ranges, const void* src, Scalar as) {
    if (!copies_ranges_at_once(ranges, true)) return Backend::write_ranges(id, ranges, src, as);
    HMSM_TRY(check_device_lost());
    for (const ElementRange& r : ranges) HMSM_TRY(check_range(id, r.first, r.count));
    HMSM_TRY(submit_held_back());
    const Shape shape = buffer_info(id).shape;
    const uint64_t element_bytes = device_element_bytes(id), scalar_bytes = as == Scalar::f64 ? 8 : 4;
    std::vector<VkBufferCopy> regions;
    regions.reserve(ranges.size());
    for (const ElementRange& r : ranges)
        if (r.count > 0) regions.push_back({r.first * element_bytes, 0, r.count * element_bytes});
    const auto* in = static_cast<const std::byte*>(src);
    HMSM_TRY(transfer_->upload_ranges(buffers_[uint32_t(id)], regions,
                                      [&](void* staging, VkDeviceSize first_byte, VkDeviceSize bytes) {
                                          scalars_to_words(shape, in + first_byte / 4 * scalar_bytes, bytes / 4,
                                                           staging, as);
                                      }));
    return device_->take_validation_messages();
}

}  // namespace hmsm::detail::vk
