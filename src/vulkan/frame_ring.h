// Live parameters of steps recorded into an engine's command buffer (hmsm/vulkan.h
// record_steps): one persistently mapped, host-coherent staging buffer per frame in flight.
// A recording writes what changed (wind table slots, force fields, instance settings) into its
// frame's slot and records copies from there into the device-local buffers, so the engine's
// submission carries the changes and hmsm neither submits nor waits. The device-local buffers
// are updated in the order the engine submits; only the host-side source needs a slot per
// frame, and a slot is written again `frames` recordings later, when the contract of
// record_steps says the frame that read it has completed.
#pragma once

#include "device.h"
#include "device_buffer.h"

#include "../element_moves.h"

#include <vector>

namespace hmsm::detail {
/// Test hook: rings created afterwards start each slot at `bytes` (0: the default), so a small
/// value makes slots grow, also in the middle of a frame's writes.
void vulkan_set_frame_slot_bytes(uint64_t bytes);
}  // namespace hmsm::detail

namespace hmsm::detail::vk {

/// Most frames in flight a simulation accepts (hmsm::vulkan::ExternalContext::frames_in_flight).
inline constexpr uint32_t kMaxFramesInFlight = 16;

class FrameRing {
public:
    /// `frames` in [1, kMaxFramesInFlight]; the slots are allocated on first use.
    FrameRing(const Device& device, uint32_t frames);

    uint32_t frames() const { return uint32_t(slots_.size()); }
    /// The slot of the frame being recorded, in [0, frames()).
    uint32_t current() const { return current_; }
    /// Moves to the next frame's slot; what the slot held before is free to overwrite.
    void next_frame();
    /// Host memory for `bytes` bytes in the current slot, which record_copies() copies to
    /// [dst_offset, dst_offset + bytes) of `dst`. A slot too small is replaced by a larger
    /// buffer; the old one lives until the slot comes round again.
    Result<void*> stage(VkBuffer dst, VkDeviceSize dst_offset, VkDeviceSize bytes);
    bool has_copies() const { return !copies_.empty(); }
    /// Records the copies staged since the last call, after a barrier that orders them behind
    /// earlier compute and transfer work on their destinations; the recorder's own leading
    /// barrier makes them visible to the dispatches that follow.
    void record_copies(VkCommandBuffer cmd);
    /// Forgets staged copies that were not recorded.
    void drop_copies() { copies_.clear(); }

private:
    struct Slot {
        Buffer buffer;
        VkDeviceSize used = 0;
        std::vector<Buffer> outgrown;  // replaced this frame, still the source of copies
    };
    struct Copy {
        VkBuffer src, dst;
        VkBufferCopy region;
    };

    const Device& device_;
    VkDeviceSize first_slot_bytes_;
    std::vector<Slot> slots_;
    uint32_t current_ = 0;
    std::vector<Copy> copies_;
    // record_copies' scratch, kept so that a frame's recording allocates nothing.
    std::vector<VkBufferCopy> regions_;
    DisjointIntervals written_;
};

}  // namespace hmsm::detail::vk
