// Live parameters of steps recorded into an engine's command buffer (hmsm/vulkan.h
// record_steps): one persistently mapped, host-coherent staging buffer per frame in flight.
// A recording writes what changed (wind table slots, force fields, instance settings) into its
// frame's slot and records copies from there into the device-local buffers, so the engine's
// submission carries the changes and hmsm neither submits nor waits. The device-local buffers
// are updated in the order the engine submits; only the host-side source needs a slot per
// frame, and a slot is written again `frames` recordings later, when the contract of
// record_steps says the frame that read it has completed.
//
// Each slot begins with a copy of the wind table (header and step slots, kWindTableBytes):
// the writes a frame makes to the table after the changes held back are recorded land there
// (stage_wind), and one copy carries them (take_wind_copy), which a replayed step records in
// its secondary (step_replay.h): a steady frame then records a single command into the engine's
// buffer. The header, written only when the wind or force fields change, is kept on the host
// as last written through any path, and a slot's copy is brought up to date before it is
// carried.
#pragma once

#include "device.h"
#include "device_buffer.h"

#include "../common/gpu_layout.h"
#include "../element_moves.h"

#include <optional>
#include <vector>

namespace hmsm::detail {
/// Test hook: rings created afterwards start each slot at `bytes` (0: the default), so a small
/// value makes slots grow, also in the middle of a frame's writes.
void vulkan_set_frame_slot_bytes(uint64_t bytes);
}  // namespace hmsm::detail

namespace hmsm::detail::vk {

/// Most frames in flight a simulation accepts (hmsm::vulkan::ExternalContext::frames_in_flight).
inline constexpr uint32_t kMaxFramesInFlight = 16;
/// The wind table (gpu_layout.h HMSM_WIND_*) and its header, in bytes.
inline constexpr VkDeviceSize kWindTableBytes = VkDeviceSize(HMSM_WIND_TABLE_ELEMENTS) * 16;
inline constexpr VkDeviceSize kWindHeaderBytes = VkDeviceSize(HMSM_WIND_STEPS) * 16;

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
    /// vkCmdCopyBuffer commands record_copies() has recorded (a test hook).
    uint64_t copy_commands() const { return copy_commands_; }

    /// The copy of the current slot's wind table that carries a frame's writes to the table.
    struct WindCopy {
        VkBuffer src = VK_NULL_HANDLE;
        VkDeviceSize bytes = 0;  // from the table's start: the header and the step slots written
    };
    /// Keeps `words` (kWindHeaderBytes, as the device stores them) as the header last written;
    /// `in_slot`: the current slot's wind table holds them already.
    void keep_wind_header(const void* words, bool in_slot);
    /// The header was written in part: none is known until it is written whole again.
    void forget_wind_header() { header_known_ = false; }
    /// Lets the current frame's wind table writes go to its slot's copy of the table (after the
    /// changes held back were recorded), until take_wind_copy().
    void open_wind_table() { wind_open_ = true; }
    /// Host memory for bytes [offset, offset + bytes) of the wind table in the current slot, or
    /// null where such a write goes through stage(): the table is not open, or the header is
    /// not known and the write does not hold it whole.
    Result<void*> stage_wind(VkDeviceSize offset, VkDeviceSize bytes);
    /// The copy of what the open table received (the header brought up to date first), if
    /// anything; closes the table, so later writes of the frame go through stage().
    std::optional<WindCopy> take_wind_copy();
    /// Records `copy` into `cmd` after a barrier as record_copies() has: the table `dst` then
    /// holds what the slot does.
    static void record_wind_copy(const Device& device, VkCommandBuffer cmd, const WindCopy& copy, VkBuffer dst);

private:
    struct Slot {
        Buffer buffer;  // the wind table first, then what stage() hands out
        VkDeviceSize used = 0;
        std::vector<Buffer> outgrown;  // replaced this frame, still the source of copies
        uint64_t header_version = 0;   // the kept header its wind table holds (0: none)
    };
    /// Replaces the slot's buffer by one of at least `bytes` (the wind table carried over).
    Status grow(Slot& slot, VkDeviceSize bytes);
    struct Copy {
        VkBuffer src, dst;
        VkBufferCopy region;
    };

    const Device& device_;
    VkDeviceSize first_slot_bytes_;
    std::vector<Slot> slots_;
    uint32_t current_ = 0;
    std::vector<Copy> copies_;
    uint64_t copy_commands_ = 0;
    std::vector<std::byte> header_ = std::vector<std::byte>(kWindHeaderBytes);  // keep_wind_header's
    uint64_t header_version_ = 0;  // numbers the kept headers (a slot's 0: none)
    bool header_known_ = false;    // header_ is the header last written
    bool wind_open_ = false;
    VkDeviceSize wind_end_ = 0;  // end of the open table's writes this frame
    // record_copies' scratch, kept so that a frame's recording allocates nothing.
    std::vector<VkBufferCopy> regions_;
    DisjointIntervals written_;
    std::vector<VkBuffer> destinations_;  // of the commands since the last barrier
};

}  // namespace hmsm::detail::vk
