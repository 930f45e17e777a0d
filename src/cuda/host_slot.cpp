#include "host_slot.h"

#include "cuda_error.h"

#include <algorithm>

namespace hmsm::detail::cuda {
namespace {

/// Growth granularity: a slot sized for one frame's output is not reallocated when the output
/// grows by a few instances.
constexpr uint64_t kGrain = 1ull << 20;

}  // namespace

HostSlot::~HostSlot() {
    if (in_flight_) (void)cudaEventSynchronize(event_);
    if (event_) (void)cudaEventDestroy(event_);
    if (pinned_) (void)cudaFreeHost(pinned_);
}

Status HostSlot::wait() {
    if (in_flight_) CUDA_TRY(cudaEventSynchronize(event_));
    in_flight_ = false;
    return {};
}

Result<std::byte*> HostSlot::acquire(uint64_t bytes) {
    HMSM_TRY(wait());
    if (pinned_ && capacity_ >= bytes) return pinned_;
    if (!pinned_ && !pageable_.empty() && pageable_.size() >= bytes) return pageable_.data();
    // Geometric growth: a slot asked for a little more each call (a streaming world's writes
    // grow with its instances) is reallocated, which pins memory anew, a logarithmic number of
    // times.
    const uint64_t held = pinned_ ? capacity_ : uint64_t(pageable_.size());
    const uint64_t grown = std::max((bytes / kGrain + 1) * kGrain, (held + held / 2) / kGrain * kGrain);
    if (pinned_) CUDA_TRY(cudaFreeHost(pinned_));
    pinned_ = nullptr;
    capacity_ = 0;
    void* host = nullptr;
    if (cudaHostAlloc(&host, grown, cudaHostAllocDefault) == cudaSuccess) {
        pinned_ = static_cast<std::byte*>(host);
        capacity_ = grown;
        pageable_ = {};
        return pinned_;
    }
    (void)cudaGetLastError();
    try {
        pageable_.resize(grown);
    } catch (const std::bad_alloc&) {
        return Status{ErrorCode::out_of_memory,
                      "cuda: not enough host memory for a staging buffer of " + std::to_string(grown) + " bytes"};
    }
    return pageable_.data();
}

Status HostSlot::mark(cudaStream_t stream) {
    if (!event_) CUDA_TRY(cudaEventCreateWithFlags(&event_, cudaEventDisableTiming));
    CUDA_TRY(cudaEventRecord(event_, stream));
    in_flight_ = true;
    return {};
}

}  // namespace hmsm::detail::cuda
