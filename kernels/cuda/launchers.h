// Host entry points of the seven CUDA passes (kernels/cuda/NAME.cu, one per pass).
//
// Every pass kernel has the same two parameters, passed by value: the device pointers of all
// buffers (BufferPointers) and the dispatch's PassConstants, or for a batched launch (a run of
// dispatches over different groups in one launch, src/common/batch_index.h) its BatchLaunch. A
// launcher enqueues its kernel on `stream` over pc.element_count threads (blocks of
// HMSM_WORKGROUP_SIZE, a grid-stride loop beyond the grid) and returns the launch error, if any.
// Because the signatures are uniform, a captured kernel node can be re-parameterized generically
// (the step graph only changes the wind slot between replays; see src/cuda/step_graph.h).
//
// emulate_NAME runs the same per-element code serially on the host over host memory laid out
// exactly like the device buffers; tests use it to check the kernel bodies on machines without
// a GPU.
#pragma once

#include "../../src/buffers.h"
#include "../../src/common/batch_index.h"
#include "../../src/common/gpu_layout.h"

#include <hmsm/pass.h>

#include <cuda_runtime_api.h>

namespace hmsm::detail::cuda {

/// Device element type of each buffer shape (a mat3x4 element is 3 consecutive float4 columns).
using DeviceType_i32 = int;
using DeviceType_i32x2 = int2;
using DeviceType_i32x4 = int4;  // instance_table (uvec4 entries stored as int32 words)
using DeviceType_f32x2 = float2;
using DeviceType_f32x4 = float4;
using DeviceType_mat3x4 = float4;
using DeviceType_f32x24 = float4;  // 6 consecutive float4 (chain_dynamics)
using DeviceType_f32x36 = float4;  // 9 consecutive float4 (instance_wind)

/// Base pointers of every buffer of the buffer table, named as in HMSM_BUFFERS.
struct BufferPointers {
#define HMSM_CUDA_POINTER(name, binding, shape, scope) DeviceType_##shape* name = nullptr;
    HMSM_BUFFERS(HMSM_CUDA_POINTER)
#undef HMSM_CUDA_POINTER
    /// CUDA only, not in the buffer table: as many elements as chain_state, where the walk that
    /// integrates ahead (HMSM_DISPATCH_WALK_AHEAD) writes the next step's angles. The backend swaps it
    /// with chain_state when a step takes them (src/cuda/cuda_backend.cpp).
    float4* chain_state_next = nullptr;
};

/// How a batched launch (src/common/batch_index.h) runs: the kind of every entry, the threads of
/// a block, the blocks of the grid (the last block prefix), and whether some entry covers paused
/// instances (the kernel variant with the check; src/cuda/launch_plan.h plans them).
struct BatchShape {
    uint32_t kind = 0;
    uint32_t threads = HMSM_WORKGROUP_SIZE;
    uint32_t blocks = 0;
    bool may_pause = false;
};

/// launch_batch_NAME enqueues one launch of a batch of dispatches of pass NAME (`batch` holds
/// device pointers); emulate_batch_NAME runs it on the host (`batch` holds host pointers), block
/// by block through the same entry search.
#define HMSM_CUDA_DECLARE_PASS(name)                                                                    \
    cudaError_t launch_##name(const BufferPointers& buffers, const gpu::PassConstants& pc,            \
                              cudaStream_t stream);                                                    \
    void emulate_##name(const BufferPointers& host_buffers, const gpu::PassConstants& pc);            \
    cudaError_t launch_batch_##name(const BufferPointers& buffers, const BatchLaunch& batch,           \
                                    const BatchShape& shape, cudaStream_t stream);                     \
    void emulate_batch_##name(const BufferPointers& host_buffers, const BatchLaunch& batch,            \
                              const BatchShape& shape);
HMSM_PASSES(HMSM_CUDA_DECLARE_PASS)
#undef HMSM_CUDA_DECLARE_PASS

}  // namespace hmsm::detail::cuda
