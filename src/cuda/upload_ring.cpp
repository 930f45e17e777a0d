#include "upload_ring.h"

#include "cuda_error.h"

#include <algorithm>
#include <string>

namespace hmsm::detail::cuda {
namespace {

/// The first ring: a moving world's frame of writes (instance winds, pattern tables, templates)
/// takes a few MiB.
constexpr uint64_t kFirstCapacity = 16ull << 20;
/// Every acquire starts on this boundary (the converted words are read as vec4s).
constexpr uint64_t kAlignment = 256;

}  // namespace

UploadRing::~UploadRing() {
    for (Region& r : in_flight_) {
        (void)cudaEventSynchronize(r.copied);
        (void)cudaEventDestroy(r.copied);
    }
    for (cudaEvent_t e : spare_events_) (void)cudaEventDestroy(e);
}

Status UploadRing::retire_oldest() {
    Region r = in_flight_.front();
    in_flight_.pop_front();
    const cudaError_t query = cudaEventQuery(r.copied);
    if (query == cudaErrorNotReady) {
        ++waits_;
        CUDA_TRY(cudaEventSynchronize(r.copied));
    } else if (query != cudaSuccess) {
        CUDA_TRY(query);
    }
    spare_events_.push_back(r.copied);
    return {};
}

Status UploadRing::grow(uint64_t bytes) {
    while (!in_flight_.empty()) HMSM_TRY(retire_oldest());
    head_ = 0;
    return memory_.allocate(std::max({kFirstCapacity, 2 * memory_.size(), 4 * bytes}), "an upload ring");
}

Result<std::byte*> UploadRing::acquire(uint64_t bytes) {
    // An acquire that was never marked enqueued no copy from its bytes (its caller failed
    // before): they are free again.
    if (pending_) head_ = last_.begin;
    pending_ = false;
    const uint64_t size = std::max<uint64_t>(kAlignment, (bytes + kAlignment - 1) / kAlignment * kAlignment);
    if (size > memory_.size() / 2) HMSM_TRY(grow(size));
    // Opportunistically forget copies that have run, so the queue stays short.
    while (!in_flight_.empty() && cudaEventQuery(in_flight_.front().copied) == cudaSuccess) HMSM_TRY(retire_oldest());
    if (head_ + size > memory_.size()) head_ = 0;
    const uint64_t begin = head_, end = head_ + size;
    // The regions still read are the oldest ones ahead of the head, in ring order: retiring from
    // the oldest frees the bytes wanted before any newer region.
    auto overlaps = [&] {
        for (const Region& r : in_flight_)
            if (r.begin < end && begin < r.end) return true;
        return false;
    };
    while (overlaps()) HMSM_TRY(retire_oldest());
    last_ = {begin, end, nullptr};
    pending_ = true;
    head_ = end;
    return memory_.data() + begin;
}

Status UploadRing::mark(cudaStream_t stream) {
    if (!pending_) return {};
    cudaEvent_t event = nullptr;
    if (!spare_events_.empty()) {
        event = spare_events_.back();
        spare_events_.pop_back();
    } else {
        CUDA_TRY(cudaEventCreateWithFlags(&event, cudaEventDisableTiming));
    }
    if (cudaError_t e = cudaEventRecord(event, stream); e != cudaSuccess) {
        spare_events_.push_back(event);
        CUDA_TRY(e);
    }
    last_.copied = event;
    in_flight_.push_back(last_);
    pending_ = false;
    return {};
}

}  // namespace hmsm::detail::cuda
