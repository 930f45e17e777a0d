// An engine's recording (hmsm/vulkan.h record_steps, docs/vulkan.md): between
// begin_recording and end_recording the backend records into the engine's command buffer, and
// writes go to the frame's ring slot (frame_ring.h) instead of being submitted: the wind table
// to the slot's copy of it, which the replayed step carries, everything else as a copy recorded
// ahead of the steps.
#include "vulkan_backend.h"

#include "../device_words.h"

#include <array>

namespace hmsm::detail::vk {

Status VulkanBackend::begin_recording(VkCommandBuffer command_buffer) {
    record_target_ = command_buffer;
    ++recordings_;
    ring_->next_frame();
    run_table_->next_recording(ring_->frames());
    HMSM_TRY(record_held_back());
    ring_->open_wind_table();
    return {};
}

Status VulkanBackend::end_recording() {
    ring_->record_copies(record_target_);
    if (const std::optional<FrameRing::WindCopy> wind = ring_->take_wind_copy()) record_wind_copy(*wind);
    record_target_ = VK_NULL_HANDLE;
    engine_recorded_ = true;
    return device_->take_validation_messages();
}

Status VulkanBackend::stage_write(BufferId id, uint64_t first, uint64_t count, const void* src, Scalar as) {
    const Shape shape = buffer_info(id).shape;
    const uint64_t scalar_bytes = as == Scalar::f64 ? 8 : 4;
    if (id == BufferId::wind_table) {
        // Into the slot's copy of the table where it is open (frame_ring.h), else as any write.
        const bool whole_header = first == 0 && count >= HMSM_WIND_STEPS;
        if (first < HMSM_WIND_STEPS && !whole_header) {
            // A part of the header: what the slot's table holds so far goes first, this after.
            ring_->forget_wind_header();
            if (const std::optional<FrameRing::WindCopy> wind = ring_->take_wind_copy()) record_wind_copy(*wind);
        }
        auto region = ring_->stage_wind(first * 16, count * 16);
        if (!region) return region.status();
        if (*region) {
            scalars_to_words(shape, src, count * 4, *region, as);
            if (whole_header) ring_->keep_wind_header(*region, true);
            return {};
        }
        keep_wind_header(first, count, src, as);  // the copy staged below carries it
    }
    auto stage = [&](const WindowPlan::Piece& piece) -> Status {
        const auto* in =
            static_cast<const std::byte*>(src) + (piece.logical - first) * shape_scalars(shape) * scalar_bytes;
        const VkDeviceSize bytes = piece.count * device_element_bytes(id);
        auto staged = ring_->stage(buffers_[uint32_t(id)].handle(), piece.physical * device_element_bytes(id), bytes);
        if (!staged) return staged.status();
        scalars_to_words(shape, in, bytes / 4, *staged, as);
        return {};
    };
    // Only a ping-pong buffer of a split scene has more than one piece (windows.h).
    if (!plan_->split() || buffer_info(id).scope != Scope::chain_halves) return stage({first, first, count});
    for (const WindowPlan::Piece& piece : plan_->pieces(id, first, count)) HMSM_TRY(stage(piece));
    return {};
}

void VulkanBackend::record_wind_copy(const FrameRing::WindCopy& copy) {
    FrameRing::record_wind_copy(*device_, record_target_, copy, buffers_[uint32_t(BufferId::wind_table)].handle());
    ++wind_copies_in_engine_buffers_;
}

void VulkanBackend::keep_wind_header(uint64_t first, uint64_t count, const void* src, Scalar as) {
    if (first >= HMSM_WIND_STEPS) return;
    if (first > 0 || count < HMSM_WIND_STEPS) return ring_->forget_wind_header();
    std::array<uint32_t, HMSM_WIND_STEPS * 4> words;
    scalars_to_words(buffer_info(BufferId::wind_table).shape, src, words.size(), words.data(), as);
    ring_->keep_wind_header(words.data(), false);
}

}  // namespace hmsm::detail::vk
