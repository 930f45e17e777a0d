// A test-only backend that runs the CUDA kernel bodies serially on the host (emulate_dispatch,
// kernels/cuda/launchers.h) over host images of the device buffers, laid out and converted
// exactly as the CUDA backend stores them (src/device_words.h). It lets the per-pass agreement
// suite check the kernels' arithmetic and indexing on machines without a GPU.
#pragma once

#include "backend.h"

#include <memory>

namespace hmsm::test {

std::unique_ptr<detail::Backend> create_cuda_emulation_backend();

}  // namespace hmsm::test
