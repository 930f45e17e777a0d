#include "device_buffers.h"

#include "cuda_error.h"
#include "device_layout.h"

#include <cuda_runtime_api.h>

#include <algorithm>
#include <cstdio>
#include <vector>

namespace hmsm::detail::cuda {
namespace {

/// Elements per host staging chunk of read/write: bounded host memory for any buffer size.
constexpr uint64_t kStagingBytes = 16ull << 20;

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
    counts_ = {};
    pointers_ = {};
}

uint64_t DeviceBuffers::bytes() const {
    uint64_t total = 0;
    for (const BufferInfo& info : kBufferTable) total += counts_[uint32_t(info.id)] * device_element_bytes(info.id);
    return total;
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
#define HMSM_CUDA_BIND(name, binding, shape, scope) \
    pointers_.name = static_cast<DeviceType_##shape*>(bases_[binding]);
    HMSM_BUFFERS(HMSM_CUDA_BIND)
#undef HMSM_CUDA_BIND
    return {};
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

Status DeviceBuffers::check_range(BufferId id, uint64_t first, uint64_t count) const {
    const uint64_t size = counts_[uint32_t(id)];
    if (first > size || count > size - first)
        return {ErrorCode::invalid_argument, "cuda: elements [" + std::to_string(first) + ", " +
                                                 std::to_string(first + count) + ") are past the end of buffer " +
                                                 std::string(buffer_info(id).name) + " (" +
                                                 std::to_string(size) + " elements)"};
    return {};
}

Status DeviceBuffers::read(BufferId id, uint64_t first, uint64_t count, void* dst, Scalar as,
                           cudaStream_t stream) const {
    HMSM_TRY(check_range(id, first, count));
    const Shape shape = buffer_info(id).shape;
    const uint64_t element_bytes = device_element_bytes(id);
    const auto* base = static_cast<const std::byte*>(bases_[uint32_t(id)]) + first * element_bytes;
    if (as == Scalar::f32 && !shape_is_integer(shape)) {  // same words on both sides
        CUDA_TRY(cudaMemcpyAsync(dst, base, count * element_bytes, cudaMemcpyDeviceToHost, stream));
        CUDA_TRY(cudaStreamSynchronize(stream));
        return {};
    }
    const uint64_t scalars = shape_scalars(shape);
    const uint64_t scalar_bytes = as == Scalar::f64 ? 8 : 4;
    const uint64_t chunk = std::max<uint64_t>(1, kStagingBytes / element_bytes);
    std::vector<std::byte> staging(std::min(count, chunk) * element_bytes);
    for (uint64_t done = 0; done < count; done += chunk) {
        const uint64_t n = std::min(chunk, count - done);
        CUDA_TRY(cudaMemcpyAsync(staging.data(), base + done * element_bytes, n * element_bytes,
                                 cudaMemcpyDeviceToHost, stream));
        CUDA_TRY(cudaStreamSynchronize(stream));
        words_to_scalars(shape, staging.data(), n * scalars,
                         static_cast<std::byte*>(dst) + done * scalars * scalar_bytes, as);
    }
    return {};
}

Status DeviceBuffers::write(BufferId id, uint64_t first, uint64_t count, const void* src,
                            Scalar as, cudaStream_t stream) {
    HMSM_TRY(check_range(id, first, count));
    const Shape shape = buffer_info(id).shape;
    const uint64_t element_bytes = device_element_bytes(id);
    auto* base = static_cast<std::byte*>(bases_[uint32_t(id)]) + first * element_bytes;
    const uint64_t scalars = shape_scalars(shape);
    const uint64_t scalar_bytes = as == Scalar::f64 ? 8 : 4;
    const uint64_t chunk = std::max<uint64_t>(1, kStagingBytes / element_bytes);
    std::vector<std::byte> staging(std::min(count, chunk) * element_bytes);
    for (uint64_t done = 0; done < count; done += chunk) {
        const uint64_t n = std::min(chunk, count - done);
        scalars_to_words(shape, static_cast<const std::byte*>(src) + done * scalars * scalar_bytes,
                         n * scalars, staging.data(), as);
        CUDA_TRY(cudaMemcpyAsync(base + done * element_bytes, staging.data(), n * element_bytes,
                                 cudaMemcpyHostToDevice, stream));
        CUDA_TRY(cudaStreamSynchronize(stream));
    }
    return {};
}

}  // namespace hmsm::detail::cuda
