// Host memory for readbacks the host takes later: a pinned (page-locked) buffer, grown as
// needed and kept, and an event marking the last copy that uses it. A slot is reused only
// after that copy has run (acquire() waits for it), so a buffer a readback fills is never
// handed out before the copy has finished. (Uploads go through upload_ring.h.)
#pragma once

#include <hmsm/status.h>

#include <cuda_runtime_api.h>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace hmsm::detail::cuda {

/// Host memory for copies: pinned where the runtime grants it, pageable where it refuses (copies
/// then run at pageable speed; still correct, the CUDA runtime stages them). Freed when it is
/// allocated again and on destruction; the owner makes sure no copy still uses it then.
class HostBuffer {
public:
    HostBuffer() = default;
    ~HostBuffer();
    HostBuffer(const HostBuffer&) = delete;
    HostBuffer& operator=(const HostBuffer&) = delete;

    /// Frees what it holds and takes `bytes` anew; out_of_memory names `what` where neither
    /// kind of memory is to be had (and then it holds nothing).
    Status allocate(uint64_t bytes, const char* what);
    std::byte* data() { return pinned_ ? pinned_ : pageable_.data(); }
    const std::byte* data() const { return pinned_ ? pinned_ : pageable_.data(); }
    uint64_t size() const { return size_; }

private:
    std::byte* pinned_ = nullptr;
    std::vector<std::byte> pageable_;
    uint64_t size_ = 0;
};

class HostSlot {
public:
    HostSlot() = default;
    ~HostSlot();
    HostSlot(const HostSlot&) = delete;
    HostSlot& operator=(const HostSlot&) = delete;

    /// Waits for the copy that last used the slot, then returns at least `bytes` of host
    /// memory: pinned, or pageable where pinned memory is refused (copies then run at
    /// pageable speed; still correct, the CUDA runtime stages them).
    Result<std::byte*> acquire(uint64_t bytes);
    /// Marks the slot as used by the copies enqueued on `stream` so far.
    Status mark(cudaStream_t stream);
    /// Waits for the marked copies; the memory acquire() returned then holds their result.
    Status wait();
    const std::byte* data() const { return memory_.data(); }

private:
    HostBuffer memory_;
    cudaEvent_t event_ = nullptr;
    bool in_flight_ = false;
};

}  // namespace hmsm::detail::cuda
