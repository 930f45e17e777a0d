// One dispatch of the step program -> the launcher of its pass (the one pass switch of the
// CUDA backend).
#pragma once

#include "../backend.h"
#include "../../kernels/cuda/launchers.h"

namespace hmsm::detail::cuda {

/// Enqueues `dispatch` on `stream`; a dispatch that reads the wind slot (reads_wind_slot) runs
/// with constants.wind.w = wind_x.
cudaError_t launch_dispatch(const Dispatch& dispatch, const BufferPointers& buffers, float wind_x,
                            cudaStream_t stream);

/// The same pass run serially on the host over host images of the buffers (tests).
void emulate_dispatch(const Dispatch& dispatch, const BufferPointers& host_buffers, float wind_x);

}  // namespace hmsm::detail::cuda
