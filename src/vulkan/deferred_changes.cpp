// Instance changes of a simulation driven by record_steps (hmsm/vulkan.h, docs/vulkan.md):
// add_instances and remove_instances within the capacity move survivors' state, write the
// added instances' state and instance data, and run the added instances' rest pose. Once the
// engine records the steps, these are held back in order and recorded at the start of the next
// record_steps, ahead of its ring copies and steps, so that the change travels in the engine's
// command buffer like the other live changes and hmsm neither submits nor waits. Any
// operation that is not itself held back (step(), read(), reset, an upload when the
// capacity grows) first submits them. A write of many ranges and a level switch's pattern
// copies are held back as one change each and go as range-copy dispatches (range_copy.h),
// submitted or, in a recording, with their tables and values staged in the frame's ring slot;
// so do a swap removal's many moves of a buffer in a recording (as a pattern copy). Between
// blocking steps the same changes are held back too (up to kBlockingHeldBytes staged) and go
// as one command buffer of hmsm's own, recorded the same way, in one submission.
#include "vulkan_backend.h"

#include "../device_words.h"
#include "../element_moves.h"

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <string_view>
#include <unordered_map>
#include <utility>

namespace hmsm::detail::vk {

namespace {

/// A range-copy dispatch in a recording comes after every earlier write and read of what it
/// writes (earlier changes, the steps of earlier frames)...
void barrier_before_dispatch(const Device& device, VkCommandBuffer cmd) {
    barrier_after_all_writes(device, cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                             VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT);
}
/// ... and later copies, dispatches and the steps see what it wrote.
void barrier_after_dispatch(const Device& device, VkCommandBuffer cmd) {
    barrier_after_all_writes(device, cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                             VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_READ_BIT |
                                 VK_ACCESS_TRANSFER_WRITE_BIT);
}

}  // namespace

bool blocking_hold_back_requested() {
    const char* env = std::getenv("HMSM_VULKAN_HOLD_BACK");
    return !(env && std::string_view(env) == "0");
}

void VulkanBackend::hold_back(HeldBack change, uint64_t staged_bytes) {
    held_back_bytes_ += staged_bytes;
    held_back_.push_back(std::move(change));
}

Status VulkanBackend::hold_back_write(BufferId id, uint64_t first, uint64_t count, const void* src, Scalar as) {
    HeldBack change{HeldBack::Kind::write, id, first, count, as};
    const uint64_t bytes = count * shape_scalars(buffer_info(id).shape) * (as == Scalar::f64 ? 8 : 4);
    change.data.resize(bytes);
    std::memcpy(change.data.data(), src, bytes);
    hold_back(std::move(change), count * device_element_bytes(id));
    return {};
}

Status VulkanBackend::submit_held_back() {
    if (held_back_.empty() || releasing_) return {};
    if (!engine_recorded_) {
        // Blocking steps: every change recorded as an engine's recording would record it, into
        // one command buffer of hmsm's own, through the frame ring's next slot (free: each such
        // submission is waited for, and no engine records into the ring).
        Status recorded;
        Status submitted = transfer_->submit([&](VkCommandBuffer cmd) {
            record_target_ = cmd;
            ++recordings_;
            ring_->next_frame();
            run_table_->next_recording(ring_->frames());
            recorded = record_held_back();
            ring_->record_copies(cmd);
            record_target_ = VK_NULL_HANDLE;
        });
        HMSM_TRY(recorded);
        HMSM_TRY(submitted);
        return device_->take_validation_messages();
    }
    std::vector<HeldBack> changes = std::exchange(held_back_, {});
    held_back_bytes_ = 0;
    releasing_ = true;
    Status status;
    for (const HeldBack& c : changes) {
        switch (c.kind) {
            case HeldBack::Kind::write: status = write(c.id, c.first, c.count, c.data.data(), c.as); break;
            case HeldBack::Kind::move: status = move_elements(c.id, c.moves); break;
            case HeldBack::Kind::run: status = run(c.program, c.steps); break;
            case HeldBack::Kind::ranges: status = write_ranges(c.id, c.ranges, c.data.data(), c.as); break;
            case HeldBack::Kind::patterns: status = patterns_now(c.ids, c.count, c.entries, c.rows); break;
        }
        if (!status) break;
    }
    releasing_ = false;
    return status;
}

Status VulkanBackend::record_held_back() {
    if (held_back_.empty()) return {};
    std::vector<HeldBack> changes = std::exchange(held_back_, {});
    held_back_bytes_ = 0;
    releasing_ = true;
    Status status;
    for (const HeldBack& c : changes) {
        switch (c.kind) {
            case HeldBack::Kind::write: status = stage_write(c.id, c.first, c.count, c.data.data(), c.as); break;
            case HeldBack::Kind::move:
                if (moves_in_frame(c.id, c.moves)) {
                    status = record_moves_in_frame(c.id, c.moves);
                    break;
                }
                ring_->record_copies(record_target_);  // the writes staged before the moves first
                record_moves(record_target_, c.id, c.moves);
                ++moves_recorded_as_copies_;
                break;
            case HeldBack::Kind::run: status = run(c.program, c.steps); break;
            case HeldBack::Kind::ranges: status = record_ranges_in_frame(c.id, c.ranges, c.data.data(), c.as); break;
            case HeldBack::Kind::patterns: status = record_patterns_in_frame(c.ids, c.count, c.entries, c.rows); break;
        }
        if (!status) break;
    }
    releasing_ = false;
    return status;
}

bool VulkanBackend::scatters_in_frame(BufferId id, std::span<const ElementRange> ranges) const {
    const BufferId ids[] = {id};
    return shader_ranges_ && ranges.size() >= kShaderRanges && plan_ && !plan_->split() && copies_by_shader(ids) &&
           !ranges_overlap(ranges) && id != BufferId::wind_table;
}

Status VulkanBackend::record_ranges_in_frame(BufferId id, std::span<const ElementRange> ranges, const void* src,
                                             Scalar as) {
    // Few ranges: a ring copy each (write() inside a recording stages them).
    if (!scatters_in_frame(id, ranges)) return Backend::write_ranges(id, ranges, src, as);
    // The scatter's own ring copies record what this recording staged before them first.
    barrier_before_dispatch(*device_, record_target_);
    const Shape shape = buffer_info(id).shape;
    uint64_t words = 0;
    const std::vector<WordSpan> scatter = packed_word_spans(ranges, device_element_bytes(id), false, words);
    HMSM_TRY(range_copier_->record_scatter_in_frame(record_target_, *ring_, recordings_, buffers_[uint32_t(id)],
                                                    scatter, words, [&](void* staged) {
                                                        scalars_to_words(shape, src, words, staged, as);
                                                    }));
    barrier_after_dispatch(*device_, record_target_);
    return device_->take_validation_messages();
}

Status VulkanBackend::record_patterns_in_frame(std::span<const BufferId> ids, uint64_t capacity,
                                               std::span<const PatternRow> entries,
                                               std::span<const PatternRow> moves) {
    std::vector<RangeCopier::PatternTarget> targets;
    for (BufferId id : ids) {
        const auto words = uint32_t(device_element_bytes(id) / 4);
        targets.push_back({&buffers_[uint32_t(id)], words, uint32_t(capacity * words), halves_of(id)});
    }
    barrier_before_dispatch(*device_, record_target_);
    HMSM_TRY(range_copier_->record_patterns_in_frame(record_target_, *ring_, recordings_, entries, moves, targets));
    barrier_after_dispatch(*device_, record_target_);
    return device_->take_validation_messages();
}

bool VulkanBackend::moves_in_frame(BufferId id, std::span<const ElementMove> moves) const {
    const BufferId ids[] = {id};
    return shader_ranges_ && moves.size() >= kShaderRanges && plan_ && !plan_->split() && copies_by_shader(ids) &&
           moves_independent(moves);
}

Status VulkanBackend::record_moves_in_frame(BufferId id, std::span<const ElementMove> moves) {
    // Elements fit 32 bits (copies_by_shader). No move reads what another writes, so the
    // pattern copy's workgroups need no order among them.
    std::vector<PatternRow> entries, patterns;
    std::unordered_map<uint64_t, uint32_t> pattern_of;  // by length: a few model levels
    entries.reserve(moves.size());
    for (const ElementMove& m : moves) {
        if (m.src == m.dst || m.count == 0) continue;
        const auto [pattern, made] = pattern_of.try_emplace(m.count, uint32_t(patterns.size()));
        if (made) patterns.push_back({0, 0, uint32_t(m.count), 0});
        entries.push_back({uint32_t(m.src), uint32_t(m.dst), pattern->second, 1});
    }
    if (entries.empty()) return {};
    // Behind every earlier command, also the engine's draws that may still read the outputs
    // (joint matrices, vertices) being moved, as record_moves.
    VkMemoryBarrier before{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    before.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
    before.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT;
    device_->vk().vkCmdPipelineBarrier(record_target_, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT,
                                       VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 1, &before, 0, nullptr, 0, nullptr);
    // The elements index the whole buffer, both halves of a ping-pong one: one half each.
    const auto words = uint32_t(device_element_bytes(id) / 4);
    const RangeCopier::PatternTarget target{&buffers_[uint32_t(id)], words, 0, 1};
    HMSM_TRY(range_copier_->record_patterns_in_frame(record_target_, *ring_, recordings_, entries, patterns,
                                                     {&target, 1}));
    barrier_after_dispatch(*device_, record_target_);
    return device_->take_validation_messages();
}

Status VulkanBackend::ensure_move_scratch(uint64_t bytes) {
    if (move_scratch_.size() >= bytes) return {};
    // A held-back move still names the scratch buffer: keep it, and record_moves goes through
    // it in pieces.
    for (const HeldBack& c : held_back_)
        if (c.kind == HeldBack::Kind::move && move_scratch_.size() > 0) return {};
    // Geometric growth: the reads, writes and moves of a streaming world ask for ever other
    // sizes, and each new allocation of device memory is a chance to fragment it.
    bytes = std::max<uint64_t>({bytes, 2 * move_scratch_.size(), uint64_t(1) << 20});
    move_scratch_ = Buffer{};
    auto scratch = Buffer::create(*device_, bytes,
                                  VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT |
                                      VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
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
    auto after_copies = [&] {
        barrier_after_all_writes(*device_, cmd, VK_PIPELINE_STAGE_TRANSFER_BIT,
                                 VK_ACCESS_TRANSFER_READ_BIT | VK_ACCESS_TRANSFER_WRITE_BIT);
    };
    if (destinations_apart_from_sources(moves)) {
        // A swap removal's moves: one copy command over all of them, no scratch.
        std::vector<VkBufferCopy> regions;
        for (const ElementMove& m : moves)
            if (m.src != m.dst && m.count > 0)
                regions.push_back({m.src * element_bytes, m.dst * element_bytes, m.count * element_bytes});
        if (!regions.empty()) vk.vkCmdCopyBuffer(cmd, buffer, buffer, uint32_t(regions.size()), regions.data());
        after_copies();
        return;
    }
    if (!batch_transfers_) return record_moves_one_by_one(cmd, id, moves);
    // Per batch: one copy gathers every source into scratch, back to back, one scatters them.
    const MoveBatches plan = plan_move_batches(moves, std::max<uint64_t>(1, move_scratch_.size() / element_bytes));
    std::vector<VkBufferCopy> gather, scatter;
    size_t begin = 0;
    for (size_t end : plan.ends) {
        gather.clear();
        scatter.clear();
        uint64_t packed = 0;
        for (size_t k = begin; k < end; ++k) {
            const ElementMove& m = plan.pieces[k];
            gather.push_back({m.src * element_bytes, packed, m.count * element_bytes});
            scatter.push_back({packed, m.dst * element_bytes, m.count * element_bytes});
            packed += m.count * element_bytes;
        }
        vk.vkCmdCopyBuffer(cmd, buffer, move_scratch_.handle(), uint32_t(gather.size()), gather.data());
        after_copies();
        vk.vkCmdCopyBuffer(cmd, move_scratch_.handle(), buffer, uint32_t(scatter.size()), scatter.data());
        after_copies();
        begin = end;
    }
}

void VulkanBackend::record_moves_one_by_one(VkCommandBuffer cmd, BufferId id, std::span<const ElementMove> moves) const {
    const VolkDeviceTable& vk = device_->vk();
    const uint64_t element_bytes = device_element_bytes(id);
    const VkBuffer buffer = buffers_[uint32_t(id)].handle();
    auto after_copies = [&] {
        barrier_after_all_writes(*device_, cmd, VK_PIPELINE_STAGE_TRANSFER_BIT,
                                 VK_ACCESS_TRANSFER_READ_BIT | VK_ACCESS_TRANSFER_WRITE_BIT);
    };
    // In order: a move apart from its own source is one copy; one that overlaps itself goes
    // through the scratch buffer in pieces, in the order for_each_chunk gives (every piece of
    // the source read before a destination piece overwrites it).
    const uint64_t piece = std::max<uint64_t>(1, move_scratch_.size() / element_bytes);
    for (const ElementMove& m : moves) {
        if (m.src == m.dst || m.count == 0) continue;
        if (!overlaps_itself(m)) {
            const VkBufferCopy direct{m.src * element_bytes, m.dst * element_bytes, m.count * element_bytes};
            vk.vkCmdCopyBuffer(cmd, buffer, buffer, 1, &direct);
            after_copies();
            continue;
        }
        (void)for_each_chunk(m, piece, [&](uint64_t src, uint64_t dst, uint64_t count) -> Status {
            const VkBufferCopy out{src * element_bytes, 0, count * element_bytes};
            vk.vkCmdCopyBuffer(cmd, buffer, move_scratch_.handle(), 1, &out);
            after_copies();
            const VkBufferCopy back{0, dst * element_bytes, count * element_bytes};
            vk.vkCmdCopyBuffer(cmd, move_scratch_.handle(), buffer, 1, &back);
            after_copies();
            return {};
        });
    }
}

}  // namespace hmsm::detail::vk
