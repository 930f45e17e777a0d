// How the GPU backends (CUDA and Vulkan) store SceneData (double) on the device: float32 and
// int32 words, a vec4 as four floats, a 3x3 matrix as three vec4 columns with w = 0
// (gpu_layout.h). Conversions for upload and for the read/write hooks of the backend interface;
// host-only, so tests can build host images of the device buffers too.
#pragma once

#include "backend.h"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace hmsm::detail {

/// Bytes of one element of `id` on the device (every scalar is a 4-byte word).
inline uint64_t device_element_bytes(BufferId id) {
    return 4ull * shape_scalars(buffer_info(id).shape);
}

/// The static (model or instance scope) buffer `id` of `scene`, as the device stores it.
std::vector<std::byte> device_image(const SceneData& scene, BufferId id);

/// Device words (int32 for integer shapes, float32 otherwise) -> float or double scalars. Float
/// words read as float keep their bits (a packed normal word may look like a signalling NaN).
void words_to_scalars(Shape shape, const void* words, uint64_t scalar_count, void* dst, Scalar as);
/// Float or double scalars -> device words: every scalar as given (a matrix column's w included,
/// which no pass reads), so write() then read() returns what was written. Integer shapes take
/// the numeric value.
void scalars_to_words(Shape shape, const void* src, uint64_t scalar_count, void* words, Scalar as);

}  // namespace hmsm::detail
