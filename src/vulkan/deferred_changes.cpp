// Instance changes of a simulation driven by record_steps (hmsm/vulkan.h, docs/vulkan.md):
// add_instances and remove_instances within the capacity move survivors' state, write the
// added instances' state and instance data, and run the added instances' rest pose. Once the
// engine records the steps, these are held back in order and recorded at the start of the next
// record_steps, ahead of its ring copies and steps, so that the change travels in the engine's
// command buffer like the other live changes and hmsm neither submits nor waits. Any
// operation that is not itself held back (step(), read(), reset, an upload when the
// capacity grows) first submits them.
#include "vulkan_backend.h"

#include "../device_words.h"

#include <algorithm>
#include <cstring>
#include <utility>

namespace hmsm::detail::vk {

Status VulkanBackend::hold_back_write(BufferId id, uint64_t first, uint64_t count, const void* src, Scalar as) {
    HeldBack change{HeldBack::Kind::write, id, first, count, as};
    const uint64_t bytes = count * shape_scalars(buffer_info(id).shape) * (as == Scalar::f64 ? 8 : 4);
    change.data.resize(bytes);
    std::memcpy(change.data.data(), src, bytes);
    held_back_.push_back(std::move(change));
    return {};
}

Status VulkanBackend::submit_held_back() {
    if (held_back_.empty() || releasing_) return {};
    std::vector<HeldBack> changes = std::exchange(held_back_, {});
    releasing_ = true;
    Status status;
    for (const HeldBack& c : changes) {
        if (c.kind == HeldBack::Kind::write) status = write(c.id, c.first, c.count, c.data.data(), c.as);
        else if (c.kind == HeldBack::Kind::move) status = move_elements(c.id, c.moves);
        else status = run(c.program, c.steps);
        if (!status) break;
    }
    releasing_ = false;
    return status;
}

Status VulkanBackend::record_held_back() {
    if (held_back_.empty()) return {};
    std::vector<HeldBack> changes = std::exchange(held_back_, {});
    releasing_ = true;
    Status status;
    for (const HeldBack& c : changes) {
        if (c.kind == HeldBack::Kind::write) {
            status = stage_write(c.id, c.first, c.count, c.data.data(), c.as);
        } else if (c.kind == HeldBack::Kind::move) {
            ring_->record_copies(record_target_);  // the writes staged before the moves first
            record_moves(record_target_, c.id, c.moves);
        } else {
            status = run(c.program, c.steps);
        }
        if (!status) break;
    }
    releasing_ = false;
    return status;
}

Status VulkanBackend::ensure_move_scratch(uint64_t bytes) {
    if (move_scratch_.size() >= bytes) return {};
    // A held-back move still names the scratch buffer: keep it, and record_moves goes through
    // it in pieces.
    for (const HeldBack& c : held_back_)
        if (c.kind == HeldBack::Kind::move) return {};
    move_scratch_ = Buffer{};
    auto scratch = Buffer::create(*device_, bytes, VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                                  MemoryUse::device_local, "state move scratch");
    if (!scratch) return scratch.status();
    move_scratch_ = std::move(scratch).value();
    return {};
}

void VulkanBackend::record_moves(VkCommandBuffer cmd, BufferId id, std::span<const ElementMove> moves) const {
    const VolkDeviceTable& vk = device_->vk();
    const uint64_t element_bytes = device_element_bytes(id);
    const VkBuffer buffer = buffers_[uint32_t(id)].handle();
    // Behind every earlier command: compute and transfer writes of the state, and the engine's
    // draws that may still read the outputs (joint matrices, vertices) being moved.
    VkMemoryBarrier before{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    before.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
    before.dstAccessMask = VK_ACCESS_TRANSFER_READ_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
    vk.vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 1, &before,
                            0, nullptr, 0, nullptr);
    // A move larger than the scratch buffer goes in pieces: front to back when it moves down
    // (each piece is read before a later piece's destination overwrites it), back to front
    // when it moves up.
    const uint64_t piece = std::max<uint64_t>(1, move_scratch_.size() / element_bytes);
    for (const ElementMove& m : moves) {
        if (m.src == m.dst || m.count == 0) continue;
        const uint64_t pieces = (m.count + piece - 1) / piece;
        for (uint64_t k = 0; k < pieces; ++k) {
            const uint64_t at = m.dst < m.src ? k * piece : (pieces - 1 - k) * piece;
            const uint64_t n = std::min(piece, m.count - at);
            const VkBufferCopy out{(m.src + at) * element_bytes, 0, n * element_bytes};
            vk.vkCmdCopyBuffer(cmd, buffer, move_scratch_.handle(), 1, &out);
            barrier_after_all_writes(*device_, cmd, VK_PIPELINE_STAGE_TRANSFER_BIT,
                                     VK_ACCESS_TRANSFER_READ_BIT | VK_ACCESS_TRANSFER_WRITE_BIT);
            const VkBufferCopy back{0, (m.dst + at) * element_bytes, n * element_bytes};
            vk.vkCmdCopyBuffer(cmd, move_scratch_.handle(), buffer, 1, &back);
            barrier_after_all_writes(*device_, cmd, VK_PIPELINE_STAGE_TRANSFER_BIT,
                                     VK_ACCESS_TRANSFER_READ_BIT | VK_ACCESS_TRANSFER_WRITE_BIT);
        }
    }
}

}  // namespace hmsm::detail::vk
