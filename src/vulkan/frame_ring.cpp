#include "frame_ring.h"

#include "../element_moves.h"

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstring>
#include <vector>

namespace hmsm::detail {
namespace {
std::atomic<uint64_t> g_first_slot_bytes{0};
}  // namespace

void vulkan_set_frame_slot_bytes(uint64_t bytes) { g_first_slot_bytes = bytes; }

namespace vk {
namespace {

/// A slot's first size: the wind table (header and 256 step slots) and as much room again.
constexpr VkDeviceSize kFirstSlotBytes = VkDeviceSize(80) << 10;
/// Staged ranges start at multiples of this (a vec4), so each copies whole elements.
constexpr VkDeviceSize kStageAlignment = 16;

}  // namespace

FrameRing::FrameRing(const Device& device, uint32_t frames)
    : device_(device), first_slot_bytes_(g_first_slot_bytes ? g_first_slot_bytes.load() : kFirstSlotBytes),
      slots_(frames) {}

void FrameRing::next_frame() {
    current_ = (current_ + 1) % uint32_t(slots_.size());
    Slot& slot = slots_[current_];
    slot.used = kWindTableBytes;
    slot.outgrown.clear();
    copies_.clear();
    wind_open_ = false;
    wind_end_ = 0;
}

Status FrameRing::grow(Slot& slot, VkDeviceSize bytes) {
    const VkDeviceSize size = std::max({first_slot_bytes_, 2 * slot.buffer.size(), bytes});
    auto grown = Buffer::create(device_, size, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, MemoryUse::staging,
                                "frame parameters");
    if (!grown) return grown.status();
    if (slot.buffer.handle()) {
        // The frame's wind table writes so far, and the header the slot holds, come along.
        std::memcpy(grown->mapped(), slot.buffer.mapped(), kWindTableBytes);
        slot.outgrown.push_back(std::move(slot.buffer));
    } else {
        slot.header_version = 0;
    }
    slot.buffer = std::move(grown).value();
    slot.used = kWindTableBytes;
    return {};
}

Result<void*> FrameRing::stage(VkBuffer dst, VkDeviceSize dst_offset, VkDeviceSize bytes) {
    Slot& slot = slots_[current_];
    const VkDeviceSize used = std::max(slot.used, kWindTableBytes);
    const VkDeviceSize offset = (used + kStageAlignment - 1) / kStageAlignment * kStageAlignment;
    if (!slot.buffer.handle() || offset + bytes > slot.buffer.size()) {
        HMSM_TRY(grow(slot, kWindTableBytes + kStageAlignment + bytes));
        return stage(dst, dst_offset, bytes);
    }
    slot.used = offset + bytes;
    copies_.push_back({slot.buffer.handle(), dst, VkBufferCopy{offset, dst_offset, bytes}});
    return static_cast<void*>(static_cast<std::byte*>(slot.buffer.mapped()) + offset);
}

void FrameRing::keep_wind_header(const void* words, bool in_slot) {
    std::memcpy(header_.data(), words, kWindHeaderBytes);
    ++header_version_;
    header_known_ = true;
    if (in_slot) slots_[current_].header_version = header_version_;
}

Result<void*> FrameRing::stage_wind(VkDeviceSize offset, VkDeviceSize bytes) {
    const bool whole_header = offset == 0 && bytes >= kWindHeaderBytes;
    if (!wind_open_ || offset + bytes > kWindTableBytes || (!header_known_ && !whole_header))
        return static_cast<void*>(nullptr);
    Slot& slot = slots_[current_];
    if (!slot.buffer.handle()) HMSM_TRY(grow(slot, kWindTableBytes));
    wind_end_ = std::max(wind_end_, offset + bytes);
    return static_cast<void*>(static_cast<std::byte*>(slot.buffer.mapped()) + offset);
}

std::optional<FrameRing::WindCopy> FrameRing::take_wind_copy() {
    const bool written = wind_open_ && wind_end_ > 0;
    wind_open_ = false;
    if (!written) return std::nullopt;
    Slot& slot = slots_[current_];
    if (slot.header_version != header_version_) {
        std::memcpy(slot.buffer.mapped(), header_.data(), kWindHeaderBytes);
        slot.header_version = header_version_;
    }
    const WindCopy copy{slot.buffer.handle(), std::max(wind_end_, kWindHeaderBytes)};
    wind_end_ = 0;
    return copy;
}

void FrameRing::record_wind_copy(const Device& device, VkCommandBuffer cmd, const WindCopy& copy, VkBuffer dst) {
    barrier_after_all_writes(device, cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT);
    const VkBufferCopy region{0, 0, copy.bytes};
    device.vk().vkCmdCopyBuffer(cmd, copy.src, dst, 1, &region);
}

void FrameRing::record_copies(VkCommandBuffer cmd) {
    if (copies_.empty()) return;
    // Earlier dispatches may still read the destinations (write-after-read) and earlier copies
    // have written them (write-after-write). The host wrote the sources before the engine's
    // submission, which makes host-coherent writes visible to the device.
    barrier_after_all_writes(device_, cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT);
    // Neighbouring copies between the same buffers go as one command while their destinations
    // stay apart (a later copy over an earlier one's bytes starts a command of its own, after a
    // barrier that keeps the order: copies without one may run in any order). Destinations in
    // ascending order are apart without a look-up; the interval index is built only for a copy
    // that starts below the end of the ones before.
    destinations_.clear();
    for (size_t k = 0; k < copies_.size();) {
        const Copy& first = copies_[k];
        regions_.clear();
        written_.clear();
        bool ascending = true;
        VkDeviceSize end = 0;
        for (; k < copies_.size() && copies_[k].src == first.src && copies_[k].dst == first.dst; ++k) {
            const VkBufferCopy& r = copies_[k].region;
            if (ascending && r.dstOffset < end) {
                ascending = false;
                for (const VkBufferCopy& earlier : regions_)
                    written_.add(earlier.dstOffset, earlier.dstOffset + earlier.size);
            }
            if (!ascending) {
                if (written_.overlaps(r.dstOffset, r.dstOffset + r.size)) break;
                written_.add(r.dstOffset, r.dstOffset + r.size);
            }
            end = std::max(end, r.dstOffset + r.size);
            regions_.push_back(r);
        }
        if (std::find(destinations_.begin(), destinations_.end(), first.dst) != destinations_.end()) {
            VkMemoryBarrier ordered{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
            ordered.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
            ordered.dstAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
            device_.vk().vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 1,
                                              &ordered, 0, nullptr, 0, nullptr);
            destinations_.clear();
        }
        destinations_.push_back(first.dst);
        device_.vk().vkCmdCopyBuffer(cmd, first.src, first.dst, uint32_t(regions_.size()), regions_.data());
        ++copy_commands_;
    }
    copies_.clear();
}

}  // namespace vk
}  // namespace hmsm::detail
