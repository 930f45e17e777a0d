// Pinned host memory for the uploads the host does not wait for, handed out in order around a
// ring. Each acquire() takes the next bytes; mark() records an event after the copies enqueued
// from them. An acquire waits only for the copies that read the bytes it hands out again, so
// the writes of one frame wait neither for one another nor for the work enqueued before them (a
// step in flight) until the ring has gone round; a ring of few fixed slots waited for the
// oldest copy of the same frame, and with it for every launch enqueued before that copy.
#pragma once

#include "host_slot.h"

#include <hmsm/status.h>

#include <cuda_runtime_api.h>

#include <cstddef>
#include <cstdint>
#include <deque>
#include <vector>

namespace hmsm::detail::cuda {

class UploadRing {
public:
    UploadRing() = default;
    ~UploadRing();
    UploadRing(const UploadRing&) = delete;
    UploadRing& operator=(const UploadRing&) = delete;

    /// At least `bytes` of host memory that no enqueued copy still reads: pinned, or pageable
    /// where pinned memory is refused (the runtime then stages the copies; still correct). A
    /// request over half the ring grows it (after every copy from it has run).
    Result<std::byte*> acquire(uint64_t bytes);
    /// Marks the bytes of the last acquire as read by the copies enqueued on `stream` so far.
    Status mark(cudaStream_t stream);

    /// Ring bytes and the acquires that had to wait for a copy (tests and benchmarks).
    uint64_t capacity() const { return memory_.size(); }
    uint64_t waits() const { return waits_; }

private:
    struct Region {
        uint64_t begin = 0, end = 0;
        cudaEvent_t copied = nullptr;
    };
    /// Waits for the oldest region's copies and returns its event to the pool.
    Status retire_oldest();
    Status grow(uint64_t bytes);

    HostBuffer memory_;
    uint64_t head_ = 0;  // the next byte handed out
    bool pending_ = false;
    Region last_;  // the last acquire's bytes, until marked
    std::deque<Region> in_flight_;  // oldest first, in ring order
    std::vector<cudaEvent_t> spare_events_;
    uint64_t waits_ = 0;
};

}  // namespace hmsm::detail::cuda
