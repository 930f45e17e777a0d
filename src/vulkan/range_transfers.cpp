// Backend::read_ranges and write_ranges of the Vulkan backend: every range of a call in one
// copy command (a region per range) to or from the transfer staging buffer, one submission
// and wait per staging-full. Inside an engine's recording or a held-back instance change the
// ranges go range by range the way write() goes (the ring, deferred_changes.cpp). Moves of
// many ranges go through the range copy (range_copy.h) in one submission per call, pattern
// copies through copy_patterns.comp, and reads and writes of many ranges through the range
// copy's gather or scatter (HMSM_VULKAN_SHADER_RANGES=0: copy regions, for side-by-side
// measurements).
#include "vulkan_backend.h"

#include "../device_words.h"

#include <algorithm>
#include <functional>
#include <vector>

namespace hmsm::detail::vk {

namespace {

/// A copy region per non-empty range, in the buffer's bytes (the transfer fills the staging
/// side, back to back).
std::vector<VkBufferCopy> buffer_regions(std::span<const ElementRange> ranges, uint64_t element_bytes) {
    std::vector<VkBufferCopy> regions;
    regions.reserve(ranges.size());
    for (const ElementRange& r : ranges)
        if (r.count > 0) regions.push_back({r.first * element_bytes, 0, r.count * element_bytes});
    return regions;
}

/// The device bytes of every range of `parts` (BufferRangesRead or BufferRangesWrite).
template <class Part>
uint64_t device_bytes(std::span<const Part> parts) {
    uint64_t bytes = 0;
    for (const Part& p : parts)
        for (const ElementRange& r : p.ranges) bytes += r.count * device_element_bytes(p.id);
    return bytes;
}

}  // namespace

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
    if (transfers_by_shader(id, ranges)) return const_cast<VulkanBackend*>(this)->shader_read(id, ranges, dst, as);
    const Shape shape = buffer_info(id).shape;
    const uint64_t element_bytes = device_element_bytes(id), scalar_bytes = as == Scalar::f64 ? 8 : 4;
    const std::vector<VkBufferCopy> regions = buffer_regions(ranges, element_bytes);
    auto* out = static_cast<std::byte*>(dst);
    HMSM_TRY(transfer_->download_ranges(buffers_[uint32_t(id)], regions,
                                        [&](const void* staging, VkDeviceSize first_byte, VkDeviceSize bytes) {
                                            words_to_scalars(shape, staging, bytes / 4,
                                                             out + first_byte / 4 * scalar_bytes, as);
                                        }));
    return device_->take_validation_messages();
}

Status VulkanBackend::write_ranges(BufferId id, std::span<const ElementRange> ranges, const void* src, Scalar as) {
    uint64_t elements = 0;
    for (const ElementRange& r : ranges) elements += r.count;
    // Held back, the values and a table row per range are staged.
    const uint64_t staged = elements * device_element_bytes(id) + ranges.size() * sizeof(PatternRow);
    const bool held_back = holding_back(staged) && batch_transfers_ && plan_ && !plan_->split() &&
                           id != BufferId::wind_table && !ranges_overlap(ranges);
    if (held_back || (record_target_ && scatters_in_frame(id, ranges))) {
        HMSM_TRY(check_device_lost());
        for (const ElementRange& r : ranges) HMSM_TRY(check_range(id, r.first, r.count));
        if (record_target_) return record_ranges_in_frame(id, ranges, src, as);
        HeldBack change{HeldBack::Kind::ranges, id};  // one change, however many ranges
        change.as = as;
        change.ranges.assign(ranges.begin(), ranges.end());
        const auto* bytes = static_cast<const std::byte*>(src);
        change.data.assign(bytes, bytes + elements * range_scalar_bytes(id, as));
        hold_back(std::move(change), staged);
        return {};
    }
    if (!copies_ranges_at_once(ranges, true)) return Backend::write_ranges(id, ranges, src, as);
    HMSM_TRY(check_device_lost());
    for (const ElementRange& r : ranges) HMSM_TRY(check_range(id, r.first, r.count));
    HMSM_TRY(submit_held_back());
    if (transfers_by_shader(id, ranges)) return shader_write(id, ranges, src, as);
    const Shape shape = buffer_info(id).shape;
    const uint64_t element_bytes = device_element_bytes(id), scalar_bytes = as == Scalar::f64 ? 8 : 4;
    const std::vector<VkBufferCopy> regions = buffer_regions(ranges, element_bytes);
    const auto* in = static_cast<const std::byte*>(src);
    HMSM_TRY(transfer_->upload_ranges(buffers_[uint32_t(id)], regions,
                                      [&](void* staging, VkDeviceSize first_byte, VkDeviceSize bytes) {
                                          scalars_to_words(shape, in + first_byte / 4 * scalar_bytes, bytes / 4,
                                                           staging, as);
                                      }));
    return device_->take_validation_messages();
}

Status VulkanBackend::read_buffers(std::span<const BufferRangesRead> reads, Scalar as) const {
    bool at_once = device_bytes(reads) <= Transfer::most_staged_bytes();
    for (const BufferRangesRead& r : reads)  // many ranges: each buffer through the range copy
        at_once = at_once && !transfers_by_shader(r.id, r.ranges) && copies_ranges_at_once(r.ranges, false);
    if (!at_once) return Backend::read_buffers(reads, as);
    HMSM_TRY(check_device_lost());
    for (const BufferRangesRead& r : reads)
        for (const ElementRange& range : r.ranges) HMSM_TRY(check_range(r.id, range.first, range.count));
    HMSM_TRY(const_cast<VulkanBackend*>(this)->submit_held_back());  // a read sees every change before it
    std::vector<std::vector<VkBufferCopy>> regions;
    std::vector<Transfer::BufferRegions> parts;
    regions.reserve(reads.size());
    for (const BufferRangesRead& r : reads)
        parts.push_back({&buffers_[uint32_t(r.id)], regions.emplace_back(buffer_regions(r.ranges, device_element_bytes(r.id)))});
    HMSM_TRY(transfer_->download_parts(parts, [&](size_t k, const void* packed) {
        uint64_t elements = 0;
        for (const ElementRange& range : reads[k].ranges) elements += range.count;
        const Shape shape = buffer_info(reads[k].id).shape;
        words_to_scalars(shape, packed, elements * shape_scalars(shape), reads[k].dst, as);
    }));
    return device_->take_validation_messages();
}

Status VulkanBackend::write_buffers(std::span<const BufferRangesWrite> writes, Scalar as) {
    bool at_once = device_bytes(writes) <= Transfer::most_staged_bytes();
    for (const BufferRangesWrite& w : writes)  // many ranges: each buffer through the range copy
        at_once = at_once && !transfers_by_shader(w.id, w.ranges) && copies_ranges_at_once(w.ranges, true);
    if (!at_once) return Backend::write_buffers(writes, as);
    HMSM_TRY(check_device_lost());
    for (const BufferRangesWrite& w : writes)
        for (const ElementRange& range : w.ranges) HMSM_TRY(check_range(w.id, range.first, range.count));
    HMSM_TRY(submit_held_back());
    std::vector<std::vector<VkBufferCopy>> regions;
    std::vector<Transfer::BufferRegions> parts;
    regions.reserve(writes.size());
    for (const BufferRangesWrite& w : writes)
        parts.push_back({&buffers_[uint32_t(w.id)], regions.emplace_back(buffer_regions(w.ranges, device_element_bytes(w.id)))});
    HMSM_TRY(transfer_->upload_parts(parts, [&](size_t k, void* packed) {
        uint64_t elements = 0;
        for (const ElementRange& range : writes[k].ranges) elements += range.count;
        const Shape shape = buffer_info(writes[k].id).shape;
        scalars_to_words(shape, writes[k].src, elements * shape_scalars(shape), packed, as);
    }));
    return device_->take_validation_messages();
}

Status VulkanBackend::move_buffers(std::span<const BufferMoves> moves) {
    if (!batch_transfers_ || holding_back() || record_target_) return Backend::move_buffers(moves);
    HMSM_TRY(check_device_lost());
    if (!capabilities().reshapes_in_place)
        return {ErrorCode::unsupported, "vulkan: a scene split into windows cannot move state in place"};
    std::vector<BufferId> ids;
    for (const BufferMoves& m : moves) ids.push_back(m.id);
    if (copies_by_shader(ids)) {
        // Every move checked first (nothing moves if one is out of range); shader_moves plans
        // the batches and sizes the scratch once.
        for (const BufferMoves& m : moves)
            HMSM_TRY(largest_move_bytes(m.moves, device_element_bytes(m.id), [&](uint64_t first, uint64_t count) {
                         return check_range(m.id, first, count);
                     }).status());
        HMSM_TRY(submit_held_back());
        return shader_moves(moves);
    }
    uint64_t staged = 0;
    for (const BufferMoves& m : moves) {
        auto bytes = move_scratch_bytes(m.id, m.moves);
        if (!bytes) return bytes.status();
        staged = std::max(staged, *bytes);
    }
    HMSM_TRY(ensure_move_scratch(staged));
    HMSM_TRY(submit_held_back());
    // One buffer's scatter and the next one's gather share the scratch: record_moves ends each
    // copy with a barrier against all earlier transfer writes and reads.
    HMSM_TRY(transfer_->submit([&](VkCommandBuffer cmd) {
        for (const BufferMoves& m : moves) record_moves(cmd, m.id, m.moves);
    }));
    return device_->take_validation_messages();
}

Status VulkanBackend::copy_patterns(std::span<const BufferId> ids, uint64_t capacity,
                                    std::span<const MovePattern> patterns, std::span<const PatternCopy> copies) {
    if (!pattern_copies_ || !copies_by_shader(ids)) return Backend::copy_patterns(ids, capacity, patterns, copies);
    HMSM_TRY(check_device_lost());
    if (!capabilities().reshapes_in_place)
        return {ErrorCode::unsupported, "vulkan: a scene split into windows cannot move state in place"};
    Result<PatternTables> tables = pattern_tables(patterns, copies);
    if (!tables) return tables.status();
    HMSM_TRY(check_pattern_ranges(*tables, ids, capacity,
                                  [&](BufferId id, uint64_t first, uint64_t count) { return check_range(id, first, count); }));
    if (tables->entries.empty() || tables->moves.empty()) return {};
    // Elements fit 32 bits: copies_by_shader holds every buffer's words within them.
    std::vector<PatternRow> entries, moves;
    for (const PatternTables::Entry& e : tables->entries)
        entries.push_back({uint32_t(e.src), uint32_t(e.dst), e.first_move, e.move_count});
    for (const ElementMove& m : tables->moves) moves.push_back({uint32_t(m.src), uint32_t(m.dst), uint32_t(m.count), 0});
    if (record_target_) return record_patterns_in_frame(ids, capacity, entries, moves);
    const uint64_t staged = (entries.size() + moves.size()) * sizeof(PatternRow);
    if (holding_back(staged)) {
        HeldBack change{HeldBack::Kind::patterns};
        change.ids.assign(ids.begin(), ids.end());
        change.count = capacity;
        change.entries = std::move(entries);
        change.rows = std::move(moves);
        hold_back(std::move(change), staged);
        return {};
    }
    HMSM_TRY(submit_held_back());
    return patterns_now(ids, capacity, entries, moves);
}

Status VulkanBackend::patterns_now(std::span<const BufferId> ids, uint64_t capacity,
                                   std::span<const PatternRow> entries, std::span<const PatternRow> moves) {
    HMSM_TRY(range_copier_->prepare(ids.size() * (entries.size() + moves.size()), uint32_t(ids.size())));
    return submit_copy_dispatches([&](VkCommandBuffer cmd, const std::function<void()>&) -> Status {
        for (BufferId id : ids) {  // the buffers are apart: no barrier between them
            const auto words = uint32_t(device_element_bytes(id) / 4);
            const uint32_t halves = halves_of(id);
            HMSM_TRY(range_copier_->record_patterns(cmd, buffers_[uint32_t(id)], entries, moves, words,
                                                    uint32_t(capacity * words), halves));
        }
        return {};
    });
}

Status VulkanBackend::shader_write(BufferId id, std::span<const ElementRange> ranges, const void* src, Scalar as) {
    // The values back to back into the scratch, then one scatter of the range copy: a copy
    // region per range costs microseconds on some drivers. Within a staging-full, the copy
    // into the scratch and the scatter go in one submission (each submission waited for costs
    // about 0.1 ms on an H200); past it, one copy command per staging-full, then the scatter.
    const Shape shape = buffer_info(id).shape;
    const uint64_t scalar_bytes = as == Scalar::f64 ? 8 : 4;
    uint64_t packed = 0;
    const std::vector<WordSpan> scatter = packed_word_spans(ranges, device_element_bytes(id), false, packed);
    if (scatter.empty()) return {};
    HMSM_TRY(ensure_move_scratch(packed * 4));
    const auto* in = static_cast<const std::byte*>(src);
    auto fill = [&](void* staging, VkDeviceSize first_byte, VkDeviceSize bytes) {
        scalars_to_words(shape, in + first_byte / 4 * scalar_bytes, bytes / 4, staging, as);
    };
    HMSM_TRY(range_copier_->prepare(scatter.size(), 1));
    auto record = [&](VkCommandBuffer cmd) {
        return range_copier_->record(cmd, buffers_[uint32_t(id)], move_scratch_, scatter, false);
    };
    if (packed * 4 <= Transfer::most_staged_bytes()) {
        HMSM_TRY(transfer_->upload_then(move_scratch_, 0, packed * 4, fill, record));
        return device_->take_validation_messages();
    }
    HMSM_TRY(transfer_->upload(move_scratch_, 0, packed * 4, fill));
    return submit_copy_dispatches([&](VkCommandBuffer cmd, const std::function<void()>&) { return record(cmd); });
}

Status VulkanBackend::shader_read(BufferId id, std::span<const ElementRange> ranges, void* dst, Scalar as) {
    // One gather of the range copy packs the ranges into the scratch, which comes back as one
    // region: a copy region per range costs microseconds on some drivers.
    const Shape shape = buffer_info(id).shape;
    const uint64_t scalar_bytes = as == Scalar::f64 ? 8 : 4;
    uint64_t packed = 0;
    const std::vector<WordSpan> gather = packed_word_spans(ranges, device_element_bytes(id), true, packed);
    if (gather.empty()) return {};
    HMSM_TRY(ensure_move_scratch(packed * 4));
    HMSM_TRY(range_copier_->prepare(gather.size(), 1));
    HMSM_TRY(submit_copy_dispatches([&](VkCommandBuffer cmd, const std::function<void()>&) {
        return range_copier_->record(cmd, buffers_[uint32_t(id)], move_scratch_, gather, true);
    }));
    auto* out = static_cast<std::byte*>(dst);
    HMSM_TRY(transfer_->download(move_scratch_, 0, packed * 4, [&](const void* staging, VkDeviceSize first_byte,
                                                                    VkDeviceSize bytes) {
        words_to_scalars(shape, staging, bytes / 4, out + first_byte / 4 * scalar_bytes, as);
    }));
    return device_->take_validation_messages();
}

bool VulkanBackend::transfers_by_shader(BufferId id, std::span<const ElementRange> ranges) const {
    const BufferId ids[] = {id};
    return shader_ranges_ && ranges.size() >= kShaderRanges && copies_by_shader(ids);
}

Status VulkanBackend::submit_copy_dispatches(
    const std::function<Status(VkCommandBuffer, const std::function<void()>&)>& record) {
    Status recorded;
    HMSM_TRY(transfer_->submit([&](VkCommandBuffer cmd) {
        const std::function<void()> barrier = [&] {
            barrier_after_all_writes(*device_, cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                                     VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT);
        };
        barrier();
        recorded = record(cmd, barrier);
        barrier();
    }));
    HMSM_TRY(recorded);
    return device_->take_validation_messages();
}

bool VulkanBackend::copies_by_shader(std::span<const BufferId> ids) const {
    if (!batch_transfers_ || !range_copier_) return false;
    for (BufferId id : ids)
        if (buffers_[uint32_t(id)].size() / 4 > UINT32_MAX) return false;
    return true;
}

Status VulkanBackend::shader_moves(std::span<const BufferMoves> moves) {
    struct Planned {
        BufferId id;
        const MoveBatches& plan;
    };
    std::vector<Planned> planned;
    uint64_t ranges = 0, scratch = 0;
    uint32_t dispatches = 0;
    std::vector<MoveBatches> plans_held;
    const std::vector<const MoveBatches*> plans =
        plan_buffer_moves(moves, [&](BufferId id) { return device_element_bytes(id); }, plans_held);
    for (size_t k = 0; k < moves.size(); ++k) {
        const MoveBatches& plan = *plans[k];
        if (plan.pieces.empty()) continue;
        ranges += 2 * plan.pieces.size();
        dispatches += 2 * uint32_t(plan.ends.size());
        scratch = std::max(scratch, plan.largest * device_element_bytes(moves[k].id));
        planned.push_back({moves[k].id, plan});
    }
    if (planned.empty()) return {};
    HMSM_TRY(ensure_move_scratch(scratch));
    HMSM_TRY(range_copier_->prepare(ranges, dispatches));
    return submit_copy_dispatches([&](VkCommandBuffer cmd, const std::function<void()>& barrier) -> Status {
        std::vector<WordSpan> gather, scatter;
        for (const Planned& p : planned) {
            const uint64_t words = device_element_bytes(p.id) / 4;
            const Buffer& buffer = buffers_[uint32_t(p.id)];
            size_t begin = 0;
            for (size_t end : p.plan.ends) {
                gather.clear();
                scatter.clear();
                uint64_t packed = 0;
                for (size_t k = begin; k < end; ++k) {
                    const ElementMove& m = p.plan.pieces[k];
                    const auto count = uint32_t(m.count * words);
                    gather.push_back({uint32_t(packed), count, uint32_t(m.src * words), 0});
                    scatter.push_back({uint32_t(packed), count, 0, uint32_t(m.dst * words)});
                    packed += count;
                }
                HMSM_TRY(range_copier_->record(cmd, buffer, move_scratch_, gather, true));
                barrier();
                HMSM_TRY(range_copier_->record(cmd, buffer, move_scratch_, scatter, false));
                barrier();
                begin = end;
            }
        }
        return {};
    });
}

}  // namespace hmsm::detail::vk
