// One dispatch of the step program -> the launcher of its pass (the one pass switch of the
// CUDA backend).
#pragma once

#include "../backend.h"
#include "../../kernels/cuda/launchers.h"

namespace hmsm::detail::cuda {

/// Enqueues `dispatch` on `stream`; a wind_force dispatch (and the fused one) runs with
/// constants.wind.w = wind_x. A fused dispatch keeps its rounds in shared memory where they fit
/// in `fused_shared_limit` bytes (fused_shared_limit() of backend.h).
cudaError_t launch_dispatch(const Dispatch& dispatch, const BufferPointers& buffers, float wind_x,
                            cudaStream_t stream, uint64_t fused_shared_limit);

/// The shared memory emulate_dispatch grants a fused dispatch by default: fused_shared_limit()
/// of an H100's opt-in maximum per block (227 KiB).
uint64_t emulated_fused_shared_limit();

/// The same pass run serially on the host over host images of the buffers (tests).
void emulate_dispatch(const Dispatch& dispatch, const BufferPointers& host_buffers, float wind_x,
                      uint64_t fused_shared_limit = emulated_fused_shared_limit());

}  // namespace hmsm::detail::cuda
