// The batched transfers of the CUDA backend: Backend::read_ranges, write_ranges and
// move_elements as a few launches of the range copy (kernels/cuda/copy_ranges.cu) between the
// buffer and a packed device scratch, whatever the number of ranges or moves. The range table
// goes to the device through the upload ring; only a read waits, once per scratch-full.
#include "device_buffers.h"

#include "cuda_error.h"
#include "../device_words.h"

#include <cuda_runtime_api.h>

#include <algorithm>
#include <cstring>
#include <vector>

namespace hmsm::detail::cuda {
namespace {

/// The most bytes one batch of range transfers packs (host staging and device scratch).
constexpr uint64_t kRangeBatchBytes = 16ull << 20;

/// Groups of consecutive ranges whose elements fit kRangeBatchBytes together; a range longer
/// than that forms a group of its own, `alone`, transferred with one plain copy.
struct RangeGroup {
    size_t begin = 0, end = 0;
    uint64_t elements = 0;
    bool alone = false;
};

std::vector<RangeGroup> range_groups(std::span<const ElementRange> ranges, uint64_t element_bytes) {
    std::vector<RangeGroup> groups;
    for (size_t k = 0; k < ranges.size(); ++k) {
        const uint64_t bytes = ranges[k].count * element_bytes;
        if (bytes > kRangeBatchBytes) {
            groups.push_back({k, k + 1, ranges[k].count, true});
            continue;
        }
        if (groups.empty() || groups.back().alone || (groups.back().elements * element_bytes + bytes > kRangeBatchBytes))
            groups.push_back({k, k, 0, false});
        groups.back().end = k + 1;
        groups.back().elements += ranges[k].count;
    }
    return groups;
}

/// The word ranges of ranges [g.begin, g.end): read from (`gather`) or written to their elements.
std::vector<WordRange> word_ranges(std::span<const ElementRange> ranges, const RangeGroup& g, uint64_t words,
                                   bool gather) {
    std::vector<ElementMove> pieces;
    pieces.reserve(g.end - g.begin);
    for (size_t k = g.begin; k < g.end; ++k)
        pieces.push_back({gather ? ranges[k].first : 0, gather ? 0 : ranges[k].first, ranges[k].count});
    std::vector<WordRange> table;
    table.reserve(pieces.size());
    append_word_ranges(table, pieces, words);
    return table;
}

}  // namespace

Status DeviceBuffers::ensure_scratch(uint64_t bytes, cudaStream_t stream) const {
    if (move_scratch_bytes_ >= bytes) return {};
    CUDA_TRY(cudaStreamSynchronize(stream));  // earlier launches may still use the scratch
    if (move_scratch_) CUDA_TRY(cudaFree(move_scratch_));
    move_scratch_ = nullptr;
    move_scratch_bytes_ = 0;
    CUDA_TRY(cudaMalloc(&move_scratch_, bytes));
    move_scratch_bytes_ = bytes;
    return {};
}

Status DeviceBuffers::upload_range_table(const std::vector<WordRange>& ranges, cudaStream_t stream) const {
    return upload_table(ranges.data(), ranges.size() * sizeof(WordRange), stream);
}

Status DeviceBuffers::upload_table(const void* data, uint64_t bytes, cudaStream_t stream) const {
    if (bytes == 0) return {};
    if (range_table_bytes_ < bytes) {
        CUDA_TRY(cudaStreamSynchronize(stream));  // earlier launches may still read the table
        const uint64_t grown = std::max<uint64_t>(bytes, 2 * range_table_bytes_);
        if (range_table_) CUDA_TRY(cudaFree(range_table_));
        range_table_ = nullptr;
        range_table_bytes_ = 0;
        CUDA_TRY(cudaMalloc(&range_table_, grown));
        range_table_bytes_ = grown;
    }
    UploadRing& slot = upload_ring();
    auto staging = slot.acquire(bytes);
    if (!staging) return staging.status();
    std::memcpy(*staging, data, bytes);
    CUDA_TRY(cudaMemcpyAsync(range_table_, *staging, bytes, cudaMemcpyHostToDevice, stream));
    return slot.mark(stream);
}

Status DeviceBuffers::copy_patterns(std::span<const BufferId> ids, uint64_t capacity,
                                    std::span<const MovePattern> patterns, std::span<const PatternCopy> copies,
                                    cudaStream_t stream) {
    // One table: the copies' entries, then every pattern's moves once.
    Result<PatternTables> tables = pattern_tables(patterns, copies);
    if (!tables) return tables.status();
    HMSM_TRY(check_pattern_ranges(*tables, ids, capacity,
                                  [&](BufferId id, uint64_t first, uint64_t count) { return check_range(id, first, count); }));
    const uint64_t entry_count = tables->entries.size();
    if (entry_count == 0 || tables->moves.empty()) return {};
    const uint64_t entries_bytes = entry_count * sizeof(PatternCopyEntry);
    std::vector<std::byte> table(entries_bytes + tables->moves.size() * sizeof(PatternMoveEntry));
    std::memcpy(table.data(), tables->entries.data(), entries_bytes);
    std::memcpy(table.data() + entries_bytes, tables->moves.data(), tables->moves.size() * sizeof(PatternMoveEntry));
    HMSM_TRY(upload_table(table.data(), table.size(), stream));
    const auto* device_entries = static_cast<const PatternCopyEntry*>(range_table_);
    const auto* device_moves =
        reinterpret_cast<const PatternMoveEntry*>(static_cast<const std::byte*>(range_table_) + entries_bytes);
    for (BufferId id : ids) {
        const uint32_t words = uint32_t(device_element_bytes(id) / 4);
        const uint32_t halves = halves_of(id);
        CUDA_TRY(launch_copy_patterns(static_cast<uint32_t*>(bases_[uint32_t(id)]), words, capacity * words, halves,
                                      device_entries, uint32_t(entry_count), device_moves, stream));
    }
    return {};
}

Status DeviceBuffers::move(BufferId id, std::span<const ElementMove> moves, cudaStream_t stream) {
    const BufferMoves one{id, moves};
    return move_buffers({&one, 1}, stream);
}

Status DeviceBuffers::move_buffers(std::span<const BufferMoves> moves, cudaStream_t stream) {
    // Per buffer: its batches (plan_move_batches) and where its entries start in the one table.
    struct Planned {
        BufferId id;
        const MoveBatches& plan;
        size_t first_entry = 0;
        std::vector<uint64_t> batch_words;
    };
    std::vector<Planned> planned;
    uint64_t scratch_bytes = 0;
    std::vector<MoveBatches> plans_held;
    const std::vector<const MoveBatches*> plans =
        plan_buffer_moves(moves, [&](BufferId id) { return device_element_bytes(id); }, plans_held);
    for (size_t k = 0; k < moves.size(); ++k) {
        const BufferMoves& m = moves[k];
        const uint64_t element_bytes = device_element_bytes(m.id);
        auto checked = largest_move_bytes(m.moves, element_bytes, [&](uint64_t first, uint64_t count) {
            return check_range(m.id, first, count);
        });
        if (!checked) return checked.status();
        if (*checked == 0) continue;
        if (!batch_transfers_) {
            HMSM_TRY(move_one_by_one(m.id, m.moves, stream));
            continue;
        }
        planned.push_back({m.id, *plans[k], 0, {}});
        scratch_bytes = std::max(scratch_bytes, planned.back().plan.largest * element_bytes);
    }
    if (planned.empty()) return {};
    HMSM_TRY(ensure_scratch(scratch_bytes, stream));
    // One table for every batch of every buffer, each batch's words packed from the scratch's start.
    std::vector<WordRange> table;
    for (Planned& p : planned) {
        p.first_entry = table.size();
        size_t begin = 0;
        for (size_t end : p.plan.ends) {
            p.batch_words.push_back(append_word_ranges(table, std::span(p.plan.pieces).subspan(begin, end - begin),
                                                       device_element_bytes(p.id) / 4));
            begin = end;
        }
    }
    HMSM_TRY(upload_range_table(table, stream));
    auto* scratch = static_cast<uint32_t*>(move_scratch_);
    for (const Planned& p : planned) {
        auto* buffer = static_cast<uint32_t*>(bases_[uint32_t(p.id)]);
        const auto* entries = static_cast<const WordRange*>(range_table_) + p.first_entry;
        size_t begin = 0;
        for (size_t b = 0; b < p.plan.ends.size(); ++b) {
            const uint32_t count = uint32_t(p.plan.ends[b] - begin);
            CUDA_TRY(launch_copy_ranges(buffer, scratch, entries + begin, count, p.batch_words[b], RangeCopy::gather,
                                        stream));
            CUDA_TRY(launch_copy_ranges(buffer, scratch, entries + begin, count, p.batch_words[b], RangeCopy::scatter,
                                        stream));
            begin = p.plan.ends[b];
        }
    }
    CUDA_TRY(cudaStreamSynchronize(stream));
    return {};
}

Status DeviceBuffers::read_buffers(std::span<const BufferRangesRead> reads, Scalar as, cudaStream_t stream) const {
    uint64_t total_bytes = 0;
    for (const BufferRangesRead& r : reads)
        for (const ElementRange& range : r.ranges) {
            HMSM_TRY(check_range(r.id, range.first, range.count));
            total_bytes += range.count * device_element_bytes(r.id);
        }
    if (!batch_transfers_ || total_bytes > kRangeBatchBytes) {
        for (const BufferRangesRead& r : reads) HMSM_TRY(read_ranges(r.id, r.ranges, r.dst, as, stream));
        return {};
    }
    if (total_bytes == 0) return {};
    HMSM_TRY(ensure_scratch(total_bytes, stream));
    // One table; buffer k's entries from first_entry[k], its words packed from word_base[k].
    std::vector<WordRange> table;
    std::vector<size_t> first_entry;
    std::vector<uint64_t> word_base, words;
    uint64_t packed = 0;
    for (const BufferRangesRead& r : reads) {
        const RangeGroup all{0, r.ranges.size(), 0, false};
        const std::vector<WordRange> own = word_ranges(r.ranges, all, device_element_bytes(r.id) / 4, true);
        first_entry.push_back(table.size());
        word_base.push_back(packed);
        words.push_back(own.empty() ? 0 : own.back().packed + own.back().words);
        table.insert(table.end(), own.begin(), own.end());
        packed += words.back();
    }
    HMSM_TRY(upload_range_table(table, stream));
    for (size_t k = 0; k < reads.size(); ++k) {
        const size_t entries = (k + 1 < reads.size() ? first_entry[k + 1] : table.size()) - first_entry[k];
        CUDA_TRY(launch_copy_ranges(static_cast<uint32_t*>(bases_[uint32_t(reads[k].id)]),
                                    static_cast<uint32_t*>(move_scratch_) + word_base[k],
                                    static_cast<const WordRange*>(range_table_) + first_entry[k], uint32_t(entries),
                                    words[k], RangeCopy::gather, stream));
    }
    auto host = range_read_slot_.acquire(total_bytes);
    if (!host) return host.status();
    CUDA_TRY(cudaMemcpyAsync(*host, move_scratch_, total_bytes, cudaMemcpyDeviceToHost, stream));
    HMSM_TRY(range_read_slot_.mark(stream));
    HMSM_TRY(range_read_slot_.wait());
    for (size_t k = 0; k < reads.size(); ++k) {
        const Shape shape = buffer_info(reads[k].id).shape;
        words_to_scalars(shape, reinterpret_cast<const uint32_t*>(*host) + word_base[k], words[k], reads[k].dst, as);
    }
    return {};
}

Status DeviceBuffers::read_ranges(BufferId id, std::span<const ElementRange> ranges, void* dst, Scalar as,
                                  cudaStream_t stream) const {
    for (const ElementRange& r : ranges) HMSM_TRY(check_range(id, r.first, r.count));
    const Shape shape = buffer_info(id).shape;
    const uint64_t element_bytes = device_element_bytes(id), host_bytes = range_scalar_bytes(id, as);
    auto* out = static_cast<std::byte*>(dst);
    if (!batch_transfers_) {
        for (const ElementRange& r : ranges) {
            HMSM_TRY(read(id, r.first, r.count, out, as, stream));
            out += r.count * host_bytes;
        }
        return {};
    }
    for (const RangeGroup& g : range_groups(ranges, element_bytes)) {
        if (g.alone) {
            HMSM_TRY(read(id, ranges[g.begin].first, ranges[g.begin].count, out, as, stream));
        } else if (g.elements > 0) {
            const uint64_t bytes = g.elements * element_bytes;
            HMSM_TRY(ensure_scratch(bytes, stream));
            const std::vector<WordRange> table = word_ranges(ranges, g, element_bytes / 4, true);
            HMSM_TRY(upload_range_table(table, stream));
            CUDA_TRY(launch_copy_ranges(static_cast<uint32_t*>(bases_[uint32_t(id)]), static_cast<uint32_t*>(move_scratch_),
                                        static_cast<const WordRange*>(range_table_), uint32_t(table.size()), bytes / 4,
                                        RangeCopy::gather, stream));
            auto host = range_read_slot_.acquire(bytes);
            if (!host) return host.status();
            CUDA_TRY(cudaMemcpyAsync(*host, move_scratch_, bytes, cudaMemcpyDeviceToHost, stream));
            HMSM_TRY(range_read_slot_.mark(stream));
            HMSM_TRY(range_read_slot_.wait());
            words_to_scalars(shape, *host, g.elements * shape_scalars(shape), out, as);
        }
        out += g.elements * host_bytes;
    }
    return {};
}

Status DeviceBuffers::write_ranges(BufferId id, std::span<const ElementRange> ranges, const void* src, Scalar as,
                                   cudaStream_t stream) {
    for (const ElementRange& r : ranges) HMSM_TRY(check_range(id, r.first, r.count));
    const Shape shape = buffer_info(id).shape;
    const uint64_t element_bytes = device_element_bytes(id), host_bytes = range_scalar_bytes(id, as);
    const auto* in = static_cast<const std::byte*>(src);
    if (!batch_transfers_ || ranges_overlap(ranges)) {  // overlapping: the later range's values stay
        for (const ElementRange& r : ranges) {
            HMSM_TRY(write(id, r.first, r.count, in, as, stream));
            in += r.count * host_bytes;
        }
        return {};
    }
    for (const RangeGroup& g : range_groups(ranges, element_bytes)) {
        if (g.alone) {
            HMSM_TRY(write(id, ranges[g.begin].first, ranges[g.begin].count, in, as, stream));
        } else if (g.elements > 0) {
            const uint64_t bytes = g.elements * element_bytes;
            HMSM_TRY(ensure_scratch(bytes, stream));
            UploadRing& slot = upload_ring();
            auto staging = slot.acquire(bytes);
            if (!staging) return staging.status();
            scalars_to_words(shape, in, g.elements * shape_scalars(shape), *staging, as);
            CUDA_TRY(cudaMemcpyAsync(move_scratch_, *staging, bytes, cudaMemcpyHostToDevice, stream));
            HMSM_TRY(slot.mark(stream));
            const std::vector<WordRange> table = word_ranges(ranges, g, element_bytes / 4, false);
            HMSM_TRY(upload_range_table(table, stream));
            CUDA_TRY(launch_copy_ranges(static_cast<uint32_t*>(bases_[uint32_t(id)]), static_cast<uint32_t*>(move_scratch_),
                                        static_cast<const WordRange*>(range_table_), uint32_t(table.size()), bytes / 4,
                                        RangeCopy::scatter, stream));
        }
        in += g.elements * host_bytes;
    }
    return {};
}

}  // namespace hmsm::detail::cuda
