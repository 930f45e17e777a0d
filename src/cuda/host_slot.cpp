#include "host_slot.h"

#include "cuda_error.h"

#include <algorithm>
#include <string>

namespace hmsm::detail::cuda {
namespace {

/// Growth granularity: a slot sized for one frame's output is not reallocated when the output
/// grows by a few instances.
constexpr uint64_t kGrain = 1ull << 20;

}  // namespace

HostBuffer::~HostBuffer() {
    if (pinned_) (void)cudaFreeHost(pinned_);
}

Status HostBuffer::allocate(uint64_t bytes, const char* what) {
    if (pinned_) CUDA_TRY(cudaFreeHost(pinned_));
    pinned_ = nullptr;
    pageable_ = {};
    size_ = 0;
    void* host = nullptr;
    if (cudaHostAlloc(&host, bytes, cudaHostAllocDefault) == cudaSuccess) {
        pinned_ = static_cast<std::byte*>(host);
    } else {
        (void)cudaGetLastError();
        try {
            pageable_.resize(bytes);
        } catch (const std::bad_alloc&) {
            return Status{ErrorCode::out_of_memory, std::string("cuda: not enough host memory for ") + what + " of " +
                                                        std::to_string(bytes) + " bytes"};
        }
    }
    size_ = bytes;
    return {};
}

HostSlot::~HostSlot() {
    if (in_flight_) (void)cudaEventSynchronize(event_);  // before memory_ is freed
    if (event_) (void)cudaEventDestroy(event_);
}

Status HostSlot::wait() {
    if (in_flight_) CUDA_TRY(cudaEventSynchronize(event_));
    in_flight_ = false;
    return {};
}

Result<std::byte*> HostSlot::acquire(uint64_t bytes) {
    HMSM_TRY(wait());
    if (memory_.size() >= bytes && memory_.size() > 0) return memory_.data();
    // Geometric growth: a slot asked for a little more each call (a streaming world's writes
    // grow with its instances) is reallocated, which pins memory anew, a logarithmic number of
    // times.
    const uint64_t held = memory_.size();
    const uint64_t grown = std::max((bytes / kGrain + 1) * kGrain, (held + held / 2) / kGrain * kGrain);
    HMSM_TRY(memory_.allocate(grown, "a staging buffer"));
    return memory_.data();
}

Status HostSlot::mark(cudaStream_t stream) {
    if (!event_) CUDA_TRY(cudaEventCreateWithFlags(&event_, cudaEventDisableTiming));
    CUDA_TRY(cudaEventRecord(event_, stream));
    in_flight_ = true;
    return {};
}

}  // namespace hmsm::detail::cuda
