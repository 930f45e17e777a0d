// The device buffers of the buffer table (buffers.h), one cudaMalloc each, sized from a
// SceneData; uploads converted to float (src/device_words.h) and the typed read/write hooks, which
// move data through pinned host memory (copies from or into pageable memory run at a fraction
// of the PCIe/NVLink rate): writes through the upload ring without waiting for the copy
// (upload_ring.h), output reads with one copy into a slot per output (host_slot.h).
#pragma once

#include "../backend.h"
#include "../element_moves.h"
#include "../../kernels/cuda/copy_ranges.h"
#include "../../kernels/cuda/launchers.h"
#include "host_slot.h"
#include "upload_ring.h"

#include <array>
#include <cstdint>

namespace hmsm::detail::cuda {

class DeviceBuffers {
public:
    DeviceBuffers() = default;
    ~DeviceBuffers();
    DeviceBuffers(const DeviceBuffers&) = delete;
    DeviceBuffers& operator=(const DeviceBuffers&) = delete;

    /// Allocates every buffer for `scene`. When the device runs out of memory, frees what it
    /// took and returns out_of_memory naming the buffer and the bytes it asked for.
    Status allocate(const SceneData& scene);
    /// Copies the static buffers and zero-fills the state buffers; complete on return.
    Status upload(const SceneData& scene, cudaStream_t stream);
    /// Backend::grow: allocates the capacity-sized buffers (and chain_state's twin) anew for
    /// `scene`, copies their live elements device to device and zeroes the rest on `stream`,
    /// then frees the old ones; complete on return. When an allocation fails, frees what it
    /// took and returns out_of_memory with every buffer as it was.
    Status grow(const SceneData& scene, cudaStream_t stream);

    /// Backend::read / Backend::write over elements [first, first + count) of `id`.
    Status read(BufferId id, uint64_t first, uint64_t count, void* dst, Scalar as,
                cudaStream_t stream) const;
    /// Up to 4 MiB (kUploadSlotBytes), a write is converted into the upload ring and
    /// copied in stream order without waiting (a later kernel on `stream` sees it; `src` may be
    /// reused at once); larger ones go through the staging buffer and are complete on return.
    Status write(BufferId id, uint64_t first, uint64_t count, const void* src, Scalar as,
                 cudaStream_t stream);

    /// Backend::request_read / take_read: elements [first, first + count) of the float buffer
    /// `id` copied into read slot `slot` with one device-to-host copy on `stream`.
    Status request_read(uint32_t slot, BufferId id, uint64_t first, uint64_t count, cudaStream_t stream) const;
    Result<const float*> take_read(uint32_t slot) const;

    /// Backend::move_elements, in stream order and complete on return: batched (the default,
    /// element_moves.h batch_transfers_enabled), one gather and one scatter launch through the
    /// scratch buffer per batch of plan_move_batches; otherwise each move one or two copies.
    Status move(BufferId id, std::span<const ElementMove> moves, cudaStream_t stream);
    /// Backend::read_ranges: per scratch-full of ranges one gather launch, one device-to-host
    /// copy and one wait (range_transfers.cpp).
    Status read_ranges(BufferId id, std::span<const ElementRange> ranges, void* dst, Scalar as,
                       cudaStream_t stream) const;
    /// Backend::read_buffers: each buffer's ranges gathered with one launch into one scratch,
    /// one device-to-host copy and one wait in all (within 16 MiB; else buffer by buffer).
    Status read_buffers(std::span<const BufferRangesRead> reads, Scalar as, cudaStream_t stream) const;
    /// Backend::move_buffers: every buffer's batches as in move(), one wait in all.
    Status move_buffers(std::span<const BufferMoves> moves, cudaStream_t stream);
    /// Backend::copy_patterns: the copies and their patterns' moves in one table (through the
    /// upload ring), one launch per buffer (both halves), in stream order without waiting.
    Status copy_patterns(std::span<const BufferId> ids, uint64_t capacity, std::span<const MovePattern> patterns,
                         std::span<const PatternCopy> copies, cudaStream_t stream);
    /// Backend::write_ranges: per scratch-full one host-to-device copy and one scatter launch,
    /// in stream order without waiting (`src` may be reused at once).
    Status write_ranges(BufferId id, std::span<const ElementRange> ranges, const void* src, Scalar as,
                        cudaStream_t stream);

    /// Makes the angles the walk ahead wrote (BufferPointers::chain_state_next) chain_state, and
    /// chain_state's old allocation the next twin: a swap of two pointers, nothing copied.
    void take_next_state();

    const BufferPointers& pointers() const { return pointers_; }
    uint64_t element_count(BufferId id) const { return counts_[uint32_t(id)]; }
    /// Device memory held, in bytes.
    uint64_t bytes() const;

private:
    void release();
    /// pointers_ from bases_ and next_state_ (after they are allocated or regrown).
    void bind_pointers();
    Status check_range(BufferId id, uint64_t first, uint64_t count) const;
    /// The pinned (page-locked) host staging buffer of read/write, two halves of
    /// kStagingBytes / 2, allocated on first use; nullptr where pinned memory is refused (the
    /// copies then go through pageable memory).
    std::byte* pinned_staging() const;

    std::array<void*, kBufferCount> bases_{};
    void* next_state_ = nullptr;  // chain_state's twin (BufferPointers::chain_state_next)
    /// Moves each as one or two copies (HMSM_BATCH_TRANSFERS=0).
    Status move_one_by_one(BufferId id, std::span<const ElementMove> moves, cudaStream_t stream);
    /// Grows the scratch of moves and range transfers to `bytes` (after the stream's work).
    Status ensure_scratch(uint64_t bytes, cudaStream_t stream) const;
    /// Copies `ranges` into the device range table (in stream order, without waiting).
    Status upload_range_table(const std::vector<WordRange>& ranges, cudaStream_t stream) const;
    /// The same for `bytes` of any table (the device table grows as needed).
    Status upload_table(const void* data, uint64_t bytes, cudaStream_t stream) const;
    /// The host memory of uploads not waited for (upload_ring.h).
    UploadRing& upload_ring() const { return upload_ring_; }

    bool batch_transfers_ = batch_transfers_enabled();
    mutable void* move_scratch_ = nullptr;  // moves and range transfers, grown on demand
    mutable uint64_t move_scratch_bytes_ = 0;
    mutable void* range_table_ = nullptr;  // WordRange entries of the last range launch
    mutable uint64_t range_table_bytes_ = 0;
    mutable HostSlot range_read_slot_;  // read_ranges' device-to-host copy
    mutable std::array<HostSlot, kReadSlots> read_slots_;
    mutable UploadRing upload_ring_;
    mutable std::byte* pinned_ = nullptr;
    mutable bool pinned_refused_ = false;
    std::array<uint64_t, kBufferCount> counts_{};
    BufferPointers pointers_;
};

}  // namespace hmsm::detail::cuda
