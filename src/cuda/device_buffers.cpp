#include "device_buffers.h"

#include "cuda_error.h"
#include "../capacity_growth.h"
#include "../device_words.h"
#include "../element_moves.h"

#include <cuda_runtime_api.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <utility>
#include <vector>

namespace hmsm::detail::cuda {
namespace {

/// Host staging of read/write: two halves, so the copy of one chunk overlaps the conversion of
/// the previous one; bounded host memory for any buffer size.
constexpr uint64_t kStagingBytes = 16ull << 20;
constexpr uint64_t kHalfStagingBytes = kStagingBytes / 2;
/// The largest write that goes through the upload ring: every per-step and live-control upload
/// (wind table, force fields, instance settings), not a scene-sized state write-back.
constexpr uint64_t kUploadSlotBytes = 4ull << 20;

std::string human_bytes(uint64_t bytes) {
    char text[64];
    std::snprintf(text, sizeof text, "%llu bytes (%.2f GiB)", static_cast<unsigned long long>(bytes),
                  double(bytes) / double(1ull << 30));
    return text;
}

}  // namespace

DeviceBuffers::~DeviceBuffers() { release(); }

void DeviceBuffers::release() {
    for (void*& base : bases_) {
        if (base) (void)cudaFree(base);
        base = nullptr;
    }
    if (next_state_) (void)cudaFree(next_state_);
    next_state_ = nullptr;
    if (pinned_) (void)cudaFreeHost(pinned_);
    pinned_ = nullptr;
    if (move_scratch_) (void)cudaFree(move_scratch_);
    move_scratch_ = nullptr;
    move_scratch_bytes_ = 0;
    if (range_table_) (void)cudaFree(range_table_);
    range_table_ = nullptr;
    range_table_bytes_ = 0;
    counts_ = {};
    pointers_ = {};
}

uint64_t DeviceBuffers::bytes() const {
    uint64_t total = 0;
    for (const BufferInfo& info : kBufferTable) total += counts_[uint32_t(info.id)] * device_element_bytes(info.id);
    return total + counts_[uint32_t(BufferId::chain_state)] * device_element_bytes(BufferId::chain_state);
}

Status DeviceBuffers::allocate(const SceneData& scene) {
    release();
    for (const BufferInfo& info : kBufferTable) {
        const uint32_t b = uint32_t(info.id);
        counts_[b] = scene.element_count(info.id);
        // Never a zero-byte allocation: every pointer a kernel receives is a valid address.
        const uint64_t bytes = std::max<uint64_t>(counts_[b] * device_element_bytes(info.id), 16);
        const cudaError_t error = cudaMalloc(&bases_[b], bytes);
        if (error != cudaSuccess) {
            bases_[b] = nullptr;
            Status status = cuda_status(error, "cudaMalloc", __FILE__, __LINE__);
            release();
            uint64_t total = 0;
            for (const BufferInfo& other : kBufferTable)
                total += scene.element_count(other.id) * device_element_bytes(other.id);
            return {status.code(), "cuda: cannot allocate buffer " + std::string(info.name) + " of " +
                                       human_bytes(bytes) + " (the scene needs " + human_bytes(total) +
                                       " of device memory): " + status.message()};
        }
    }
    // chain_state's twin, for the walk that integrates ahead.
    const uint64_t state_bytes =
        std::max<uint64_t>(counts_[uint32_t(BufferId::chain_state)] * device_element_bytes(BufferId::chain_state), 16);
    if (const cudaError_t error = cudaMalloc(&next_state_, state_bytes); error != cudaSuccess) {
        next_state_ = nullptr;
        const Status status = cuda_status(error, "cudaMalloc", __FILE__, __LINE__);
        release();
        return {status.code(), "cuda: cannot allocate the next-step angles of " + human_bytes(state_bytes) + ": " +
                                   status.message()};
    }
    bind_pointers();
    return {};
}

void DeviceBuffers::take_next_state() {
    std::swap(bases_[uint32_t(BufferId::chain_state)], next_state_);
    std::swap(pointers_.chain_state, pointers_.chain_state_next);
}

Status DeviceBuffers::upload(const SceneData& scene, cudaStream_t stream) {
    for (const BufferInfo& info : kBufferTable) {
        const uint32_t b = uint32_t(info.id);
        const uint64_t bytes = counts_[b] * device_element_bytes(info.id);
        if (bytes == 0) continue;
        if (is_static(info.id)) {
            std::vector<std::byte> image = device_image(scene, info.id);
            if (image.size() != bytes)
                return {ErrorCode::internal, "cuda: size mismatch uploading " + std::string(info.name)};
            CUDA_TRY(cudaMemcpyAsync(bases_[b], image.data(), bytes, cudaMemcpyHostToDevice, stream));
            CUDA_TRY(cudaStreamSynchronize(stream));  // `image` dies at the end of this iteration
        } else {
            CUDA_TRY(cudaMemsetAsync(bases_[b], 0, bytes, stream));
        }
    }
    CUDA_TRY(cudaStreamSynchronize(stream));
    return {};
}

Status DeviceBuffers::grow(const SceneData& scene, cudaStream_t stream) {
    std::array<void*, kBufferCount> fresh{};
    std::array<GrowthPlan, kBufferCount> plans;
    void* fresh_twin = nullptr;
    auto release_fresh = [&] {
        for (void*& base : fresh) {
            if (base) (void)cudaFree(base);
            base = nullptr;
        }
        if (fresh_twin) (void)cudaFree(fresh_twin);
        fresh_twin = nullptr;
    };
    auto allocate = [&](void*& base, uint64_t bytes, const std::string& what) -> Status {
        if (const cudaError_t error = cudaMalloc(&base, bytes); error != cudaSuccess) {
            base = nullptr;
            const Status status = cuda_status(error, "cudaMalloc", __FILE__, __LINE__);
            release_fresh();
            return {status.code(), "cuda: cannot grow " + what + " to " + human_bytes(bytes) + ": " + status.message()};
        }
        return {};
    };
    for (const BufferInfo& info : kBufferTable) {
        const uint32_t b = uint32_t(info.id);
        const uint64_t count = scene.element_count(info.id);
        plans[b] = growth_plan(info.id, counts_[b], count, live_elements(scene, info.id));
        if (!plans[b].reallocates) continue;
        if (count < counts_[b]) {
            release_fresh();
            return {ErrorCode::internal, "cuda: grow() would shrink buffer " + std::string(info.name)};
        }
        HMSM_TRY(allocate(fresh[b], std::max<uint64_t>(count * device_element_bytes(info.id), 16),
                          "buffer " + std::string(info.name)));
    }
    const uint32_t state = uint32_t(BufferId::chain_state);
    if (plans[state].reallocates)  // the twin is written by the walk ahead before it is read
        HMSM_TRY(allocate(fresh_twin, std::max<uint64_t>(scene.element_count(BufferId::chain_state) *
                                                              device_element_bytes(BufferId::chain_state),
                                                          16),
                          "the next-step angles"));
    // The live elements device to device, the rest zeroed, in stream order after all earlier work.
    auto enqueue = [&]() -> cudaError_t {
        for (const BufferInfo& info : kBufferTable) {
            const uint32_t b = uint32_t(info.id);
            const uint64_t element_bytes = device_element_bytes(info.id);
            auto* to = static_cast<std::byte*>(fresh[b]);
            const auto* from = static_cast<const std::byte*>(bases_[b]);
            for (const GrowthCopy& c : plans[b].copies)
                if (cudaError_t e = cudaMemcpyAsync(to + c.dst * element_bytes, from + c.src * element_bytes,
                                                    c.count * element_bytes, cudaMemcpyDeviceToDevice, stream);
                    e != cudaSuccess)
                    return e;
            for (const GrowthZero& z : plans[b].zeros)
                if (cudaError_t e = cudaMemsetAsync(to + z.first * element_bytes, 0, z.count * element_bytes, stream);
                    e != cudaSuccess)
                    return e;
        }
        return cudaStreamSynchronize(stream);
    };
    if (const cudaError_t error = enqueue(); error != cudaSuccess) {
        (void)cudaStreamSynchronize(stream);
        release_fresh();
        return cuda_status(error, "cudaMemcpyAsync (growing the buffers)", __FILE__, __LINE__);
    }
    for (const BufferInfo& info : kBufferTable) {
        const uint32_t b = uint32_t(info.id);
        if (!plans[b].reallocates) continue;
        (void)cudaFree(bases_[b]);
        bases_[b] = std::exchange(fresh[b], nullptr);
        counts_[b] = scene.element_count(info.id);
    }
    if (fresh_twin) {
        (void)cudaFree(next_state_);
        next_state_ = std::exchange(fresh_twin, nullptr);
    }
    bind_pointers();
    return {};
}

void DeviceBuffers::bind_pointers() {
#define HMSM_CUDA_BIND(name, binding, shape, scope) \
    pointers_.name = static_cast<DeviceType_##shape*>(bases_[binding]);
    HMSM_BUFFERS(HMSM_CUDA_BIND)
#undef HMSM_CUDA_BIND
    pointers_.chain_state_next = static_cast<float4*>(next_state_);
}

Status DeviceBuffers::move_one_by_one(BufferId id, std::span<const ElementMove> moves, cudaStream_t stream) {
    const uint64_t element_bytes = device_element_bytes(id);
    auto checked = largest_move_bytes(moves, element_bytes,
                                      [&](uint64_t first, uint64_t count) { return check_range(id, first, count); });
    if (!checked) return checked.status();
    if (*checked == 0) return {};
    // A move that overlaps itself goes through scratch, at most kMoveScratchBytes at a time;
    // any other is one copy on the stream, which orders the moves as listed.
    uint64_t staged = 0;
    for (const ElementMove& m : moves)
        if (overlaps_itself(m)) staged = std::max(staged, std::min(m.count * element_bytes, kMoveScratchBytes));
    HMSM_TRY(ensure_scratch(staged, stream));
    auto* base = static_cast<std::byte*>(bases_[uint32_t(id)]);
    const uint64_t chunk_elements = std::max<uint64_t>(1, kMoveScratchBytes / element_bytes);
    for (const ElementMove& m : moves) {
        if (m.src == m.dst || m.count == 0) continue;
        if (!overlaps_itself(m)) {
            CUDA_TRY(cudaMemcpyAsync(base + m.dst * element_bytes, base + m.src * element_bytes,
                                     m.count * element_bytes, cudaMemcpyDeviceToDevice, stream));
            continue;
        }
        HMSM_TRY(for_each_chunk(m, chunk_elements, [&](uint64_t src, uint64_t dst, uint64_t count) -> Status {
            const uint64_t bytes = count * element_bytes;
            std::byte* const at = base + dst * element_bytes;
            CUDA_TRY(cudaMemcpyAsync(move_scratch_, base + src * element_bytes, bytes, cudaMemcpyDeviceToDevice,
                                     stream));
            CUDA_TRY(cudaMemcpyAsync(at, move_scratch_, bytes, cudaMemcpyDeviceToDevice, stream));
            return {};
        }));
    }
    CUDA_TRY(cudaStreamSynchronize(stream));
    return {};
}

Status DeviceBuffers::check_range(BufferId id, uint64_t first, uint64_t count) const {
    const uint64_t size = counts_[uint32_t(id)];
    if (first > size || count > size - first)
        return {ErrorCode::invalid_argument, "cuda: elements [" + std::to_string(first) + ", " +
                                                 std::to_string(first + count) + ") are past the end of buffer " +
                                                 std::string(buffer_info(id).name) + " (" +
                                                 std::to_string(size) + " elements)"};
    return {};
}

std::byte* DeviceBuffers::pinned_staging() const {
    if (!pinned_ && !pinned_refused_) {
        void* host = nullptr;
        if (cudaMallocHost(&host, kStagingBytes) == cudaSuccess) {
            pinned_ = static_cast<std::byte*>(host);
        } else {
            (void)cudaGetLastError();
            pinned_refused_ = true;
        }
    }
    return pinned_;
}

Status DeviceBuffers::read(BufferId id, uint64_t first, uint64_t count, void* dst, Scalar as,
                           cudaStream_t stream) const {
    HMSM_TRY(check_range(id, first, count));
    if (count == 0) return {};
    const Shape shape = buffer_info(id).shape;
    const uint64_t element_bytes = device_element_bytes(id);
    const auto* base = static_cast<const std::byte*>(bases_[uint32_t(id)]) + first * element_bytes;
    const uint64_t scalars = shape_scalars(shape);
    const uint64_t scalar_bytes = as == Scalar::f64 ? 8 : 4;
    const bool same_words = as == Scalar::f32 && !shape_is_integer(shape);
    std::byte* pinned = pinned_staging();
    if (!pinned && same_words) {  // pageable fallback: straight into the caller's memory
        CUDA_TRY(cudaMemcpyAsync(dst, base, count * element_bytes, cudaMemcpyDeviceToHost, stream));
        CUDA_TRY(cudaStreamSynchronize(stream));
        return {};
    }
    const uint64_t chunk = std::max<uint64_t>(1, kHalfStagingBytes / element_bytes);
    const uint64_t half_bytes = pinned ? kHalfStagingBytes : std::min(count, chunk) * element_bytes;
    std::vector<std::byte> pageable(pinned ? 0 : 2 * half_bytes);
    std::byte* staging = pinned ? pinned : pageable.data();
    std::byte* halves[2] = {staging, staging + half_bytes};
    // Chunk k is copied into half k % 2; the copy of chunk k + 1 is queued before chunk k is
    // converted, so the two overlap.
    auto queue_copy = [&](uint64_t k) -> Status {
        const uint64_t done = k * chunk;
        CUDA_TRY(cudaMemcpyAsync(halves[k % 2], base + done * element_bytes,
                                 std::min(chunk, count - done) * element_bytes, cudaMemcpyDeviceToHost, stream));
        return {};
    };
    const uint64_t chunks = (count + chunk - 1) / chunk;
    HMSM_TRY(queue_copy(0));
    CUDA_TRY(cudaStreamSynchronize(stream));
    for (uint64_t k = 0; k < chunks; ++k) {
        if (k + 1 < chunks) HMSM_TRY(queue_copy(k + 1));
        const uint64_t done = k * chunk, n = std::min(chunk, count - done);
        auto* out = static_cast<std::byte*>(dst) + done * scalars * scalar_bytes;
        words_to_scalars(shape, halves[k % 2], n * scalars, out, as);
        CUDA_TRY(cudaStreamSynchronize(stream));
    }
    return {};
}

Status DeviceBuffers::request_read(uint32_t slot, BufferId id, uint64_t first, uint64_t count,
                                   cudaStream_t stream) const {
    HMSM_TRY(check_range(id, first, count));
    if (slot >= kReadSlots || shape_is_integer(buffer_info(id).shape))
        return {ErrorCode::internal, "cuda: read slot " + std::to_string(slot) + " of buffer " +
                                         std::string(buffer_info(id).name) + " is not an output read"};
    const uint64_t bytes = count * device_element_bytes(id);
    HostSlot& host = read_slots_[slot];
    auto target = host.acquire(bytes);
    if (!target) return target.status();
    if (bytes > 0) {
        const auto* base = static_cast<const std::byte*>(bases_[uint32_t(id)]) + first * device_element_bytes(id);
        CUDA_TRY(cudaMemcpyAsync(*target, base, bytes, cudaMemcpyDeviceToHost, stream));
    }
    return host.mark(stream);
}

Result<const float*> DeviceBuffers::take_read(uint32_t slot) const {
    if (slot >= kReadSlots) return Status{ErrorCode::internal, "cuda: no read slot " + std::to_string(slot)};
    HMSM_TRY(read_slots_[slot].wait());
    return reinterpret_cast<const float*>(read_slots_[slot].data());
}

Status DeviceBuffers::write(BufferId id, uint64_t first, uint64_t count, const void* src,
                            Scalar as, cudaStream_t stream) {
    HMSM_TRY(check_range(id, first, count));
    const Shape shape = buffer_info(id).shape;
    const uint64_t element_bytes = device_element_bytes(id);
    auto* base = static_cast<std::byte*>(bases_[uint32_t(id)]) + first * element_bytes;
    const uint64_t scalars = shape_scalars(shape);
    const uint64_t scalar_bytes = as == Scalar::f64 ? 8 : 4;
    if (count == 0) return {};
    if (count * element_bytes <= kUploadSlotBytes) {
        // Converted into the upload ring, which waits only where it has gone round since.
        UploadRing& slot = upload_ring();
        auto staging = slot.acquire(count * element_bytes);
        if (!staging) return staging.status();
        scalars_to_words(shape, src, count * scalars, *staging, as);
        CUDA_TRY(cudaMemcpyAsync(base, *staging, count * element_bytes, cudaMemcpyHostToDevice, stream));
        return slot.mark(stream);
    }
    const uint64_t chunk = std::max<uint64_t>(1, kHalfStagingBytes / element_bytes);
    std::byte* pinned = pinned_staging();
    std::vector<std::byte> pageable(pinned ? 0 : std::min(count, chunk) * element_bytes);
    std::byte* staging = pinned ? pinned : pageable.data();
    for (uint64_t done = 0; done < count; done += chunk) {
        const uint64_t n = std::min(chunk, count - done);
        scalars_to_words(shape, static_cast<const std::byte*>(src) + done * scalars * scalar_bytes,
                         n * scalars, staging, as);
        CUDA_TRY(cudaMemcpyAsync(base + done * element_bytes, staging, n * element_bytes,
                                 cudaMemcpyHostToDevice, stream));
        CUDA_TRY(cudaStreamSynchronize(stream));
    }
    return {};
}

}  // namespace hmsm::detail::cuda
