// A test-only backend that runs the CUDA kernel bodies serially on the host (emulate_dispatch,
// kernels/cuda/launchers.h) over host images of the device buffers, laid out and converted
// exactly as the CUDA backend stores them (src/device_words.h). It lets the per-pass agreement
// suite check the kernels' arithmetic and indexing on machines without a GPU.
#pragma once

#include "backend.h"

#include <cstdint>
#include <memory>

namespace hmsm::test {

/// What an emulated run did with the walk that integrates ahead (AheadStep), step by step.
struct EmulatedAheadSteps {
    uint64_t taken = 0, plain = 0;
};

/// `ahead`: where not null, the backend can walk ahead (BackendCapabilities::walks_ahead), keeping
/// chain_state's twin as the CUDA backend does, and counts its steps there. `batch_runs`: runs of
/// dispatches over different groups run as the CUDA backend's batched launches (src/cuda/
/// launch_plan.h), block by block through the same entry search; false: dispatch by dispatch.
/// `max_blocks`: the grid cap of the batches' per-element entries (0: HMSM_CUDA_MAX_BLOCKS's).
std::unique_ptr<detail::Backend> create_cuda_emulation_backend(EmulatedAheadSteps* ahead = nullptr,
                                                               bool batch_runs = true, uint32_t max_blocks = 0);

}  // namespace hmsm::test
