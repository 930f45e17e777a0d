// One dispatch of the step program -> the launcher of its pass (the one pass switch of the
// CUDA backend).
#pragma once

#include "../backend.h"
#include "../../kernels/cuda/launchers.h"

namespace hmsm::detail::cuda {

/// Enqueues `dispatch` on `stream`; a dispatch that reads the wind slot (reads_wind_slot) runs
/// with constants.wind_slot = wind_slot.
cudaError_t launch_dispatch(const Dispatch& dispatch, const BufferPointers& buffers, uint32_t wind_slot,
                            cudaStream_t stream);

/// The same pass run serially on the host over host images of the buffers (tests).
void emulate_dispatch(const Dispatch& dispatch, const BufferPointers& host_buffers, uint32_t wind_slot);

}  // namespace hmsm::detail::cuda
