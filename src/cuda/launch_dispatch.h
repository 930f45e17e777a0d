// One dispatch of the step program -> the launcher of its pass (the one pass switch of the
// CUDA backend).
#pragma once

#include "../backend.h"
#include "../../kernels/cuda/launchers.h"

namespace hmsm::detail::cuda {

/// Most blocks of a per-element launch (HMSM_CUDA_MAX_BLOCKS; kernels/cuda/pass_math.cuh).
uint32_t max_launch_blocks();

/// Enqueues `dispatch` on `stream`; a dispatch that reads the wind slot (reads_wind_slot) runs
/// with constants.wind_slot = wind_slot.
cudaError_t launch_dispatch(const Dispatch& dispatch, const BufferPointers& buffers, uint32_t wind_slot,
                            cudaStream_t stream);

/// The same pass run serially on the host over host images of the buffers (tests).
void emulate_dispatch(const Dispatch& dispatch, const BufferPointers& host_buffers, uint32_t wind_slot);

/// Enqueues a batched launch of dispatches of `pass` (launch_batch_NAME; launch_plan.h plans them).
cudaError_t launch_batch(Pass pass, const BufferPointers& buffers, const BatchLaunch& batch,
                         const BatchShape& shape, cudaStream_t stream);
/// The same on the host (`batch` over host copies of its table).
void emulate_batch(Pass pass, const BufferPointers& host_buffers, const BatchLaunch& batch, const BatchShape& shape);

}  // namespace hmsm::detail::cuda
