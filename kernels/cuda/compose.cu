// Pass 3: total rotation R_c = R_parent T_c, accumulated down the chain tree.
// Pointer jumping (the paper's M_temp): round r replaces each chain's partial product P by
// P(2^r-th ancestor) P, reading half src_half of chain_rotation and writing half dst_half
// (round 0 starts from T), so after ceil(log2(D+1)) rounds P is the full product (compose_jump,
// chain_math.cuh). JUMP_ROUNDS_IN_DISPATCH runs every round in one launch, one block per
// instance, __syncthreads() between rounds. LEVEL: one depth per dispatch, R = R_parent T in
// place in the pose half (dst_half), the parent having been written by the previous dispatch.
// The walk kinds (gpu_layout.h): passes 3 and 5 together, each chain walking its ancestors from
// the trunk down (chain_math.cuh path_walk), and the walk that integrates ahead.
#include "chain_math.cuh"

namespace hmsm::detail::cuda {

static HMSM_HOST_DEVICE void compose_element(const BufferPointers& b,
                                             const gpu::PassConstants& pc, uint32_t i) {
    switch (pc.kind) {
#ifndef __CUDA_ARCH__  // the device runs walk_kernel and walk_ahead_kernel instead (launch_compose)
        case HMSM_DISPATCH_WALK_TOP_POSES: {
            const Element e = element_of(i, pc.level_count);
            return walk_top_pose(b, pc, e.instance, int32_t(e.index));
        }
        case HMSM_DISPATCH_WALK_AHEAD: {
            const Element e = element_of(i, pc.model_chain_count);
            return walk_ahead(b, pc, e.instance, int32_t(e.index));
        }
        case HMSM_DISPATCH_POSE_WALK_FROM_RECORDS:
        case HMSM_DISPATCH_POSE_WALK: {
            const Element e = element_of(i, pc.model_chain_count);
            if (instance_paused(b, pc, e.instance)) return;
            if (pc.kind == HMSM_DISPATCH_POSE_WALK_FROM_RECORDS)
                return path_walk<true>(b, pc, e.instance, int32_t(e.index));
            return path_walk<false>(b, pc, e.instance, int32_t(e.index));  // and root_positions
        }
#endif
        case HMSM_DISPATCH_LEVEL: {
            const LevelChain l = level_chain(b, pc, i);
            if (instance_paused(b, pc, l.instance)) return;
            Mat3 rotation = load_mat3(b.chain_local, l.chain);
            if (l.parent >= 0)
                rotation = load_mat3(b.chain_rotation, l.dst + state_chain(pc, l.instance, l.parent)) * rotation;
            store_mat3(b.chain_rotation, l.dst + l.chain, rotation);
            return;
        }
        default: {  // HMSM_DISPATCH_JUMP_ROUND
            const Element e = element_of(i, pc.model_chain_count);
            if (instance_paused(b, pc, e.instance)) return;
            compose_jump<false>(b, pc, e.instance, e.index, pc.round, pc.src_half, pc.dst_half);
        }
    }
}

/// Path walk on the device: a kernel of its own per way of reading the walk records, so that
/// neither way's registers weigh on the other or on the pointer-jumping kernel.
/// With the records (one instance, where a step is bound by latency), a thread's first chain's
/// record is read and its static rows asked into L1 before the kernel waits for the wind pair
/// (begin_pass's halves, pass_math.cuh), so those loads overlap the wind pair's end.
template <bool kFromRecords>
__global__ void __launch_bounds__(HMSM_WORKGROUP_SIZE)
    walk_kernel(const BufferPointers b, const gpu::PassConstants pc) {
    uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    if constexpr (kFromRecords) {
        let_next_pass_start();
        WalkRecord first{};
        const bool has_first = i < pc.element_count;
        const int32_t c = int32_t(i % pc.model_chain_count);
        if (has_first) {
            first = load_walk_record(b, pc, c);
            prefetch_walk(b, pc, c, first);
        }
        wait_for_previous_pass();
        // (No pause check: a scene of one active instance, and a group covers paused instances
        // only between active ones.)
        if (has_first) path_walk<true>(b, pc, i / pc.model_chain_count, c, &first);
        i += gridDim.x * blockDim.x;
    } else {
        begin_pass();
    }
    for (; i < pc.element_count; i += gridDim.x * blockDim.x) {
        const Element e = element_of(i, pc.model_chain_count);
        if (!instance_paused(b, pc, e.instance)) path_walk<kFromRecords>(b, pc, e.instance, int32_t(e.index));
    }
}

/// The walk that integrates ahead (gpu_layout.h): its top poses (kTopPoses) and the walk ahead.
/// Their programs cover no paused instance (step_program.cpp), so neither checks.
template <bool kTopPoses>
__global__ void __launch_bounds__(HMSM_WORKGROUP_SIZE)
    walk_ahead_kernel(const BufferPointers b, const gpu::PassConstants pc) {
    begin_pass();
    const uint32_t per_instance = kTopPoses ? pc.level_count : pc.model_chain_count;
    for (uint32_t i = blockIdx.x * blockDim.x + threadIdx.x; i < pc.element_count; i += gridDim.x * blockDim.x) {
        const Element e = element_of(i, per_instance);
        if constexpr (kTopPoses) walk_top_pose(b, pc, e.instance, int32_t(e.index));
        else walk_ahead(b, pc, e.instance, int32_t(e.index));
    }
}

HMSM_CUDA_ROUNDS_PASS_TYPE(compose)

namespace {
/// The work of one thread of a listed compose dispatch, every kind (the walk kinds as their
/// kernels' loop bodies; the constants are rebased to one active instance, so no pause check).
struct ListedComposeItems {
    using Index = uint32_t;
    static HMSM_HOST_DEVICE void item(const BufferPointers& b, const gpu::PassConstants& pc, Index i) {
        switch (pc.kind) {
            case HMSM_DISPATCH_WALK_TOP_POSES: return walk_top_pose(b, pc, 0, int32_t(i));
            case HMSM_DISPATCH_WALK_AHEAD: return walk_ahead(b, pc, 0, int32_t(i));
            case HMSM_DISPATCH_POSE_WALK_FROM_RECORDS: return path_walk<true>(b, pc, 0, int32_t(i));
            case HMSM_DISPATCH_POSE_WALK: return path_walk<false>(b, pc, 0, int32_t(i));
            default: return compose_element(b, pc, i);  // LEVEL, JUMP_ROUND
        }
    }
};
}  // namespace

cudaError_t launch_compose(const BufferPointers& b, const gpu::PassConstants& pc, cudaStream_t stream) {
    if (pc.element_count == 0) return cudaSuccess;
    if (pc.instance_list != 0) return launch_listed<ListedComposeItems, compose_pass>(b, pc, stream);
    const unsigned blocks = launch_blocks(pc.element_count);
    switch (pc.kind) {
        case HMSM_DISPATCH_POSE_WALK_FROM_RECORDS:
            return launch_pass(walk_kernel<true>, blocks, HMSM_WORKGROUP_SIZE, stream, b, pc);
        case HMSM_DISPATCH_POSE_WALK:
            return launch_pass(walk_kernel<false>, blocks, HMSM_WORKGROUP_SIZE, stream, b, pc);
        case HMSM_DISPATCH_WALK_TOP_POSES:
            return launch_pass(walk_ahead_kernel<true>, blocks, HMSM_WORKGROUP_SIZE, stream, b, pc);
        case HMSM_DISPATCH_WALK_AHEAD:
            return launch_pass(walk_ahead_kernel<false>, blocks, HMSM_WORKGROUP_SIZE, stream, b, pc);
        default: return launch<compose_pass>(b, pc, stream);  // JUMP_ROUND, JUMP_ROUNDS_IN_DISPATCH, LEVEL
    }
}

void emulate_compose(const BufferPointers& b, const gpu::PassConstants& pc) { emulate<compose_pass>(b, pc); }

namespace {

/// The items of the walk kinds in a batched launch: the loop bodies of walk_kernel (whose
/// records kernel's first-chain prefetch only moves loads earlier) and walk_ahead_kernel.
template <bool kFromRecords>
struct PoseWalkItems {
    using Index = uint32_t;
    static HMSM_HOST_DEVICE Index count(const gpu::PassConstants& pc) { return pc.element_count; }
    static HMSM_HOST_DEVICE void item(const BufferPointers& b, const gpu::PassConstants& pc, Index i) {
        const Element e = element_of(i, pc.model_chain_count);
        if (!instance_paused(b, pc, e.instance)) path_walk<kFromRecords>(b, pc, e.instance, int32_t(e.index));
    }
};
template <bool kTopPoses>
struct WalkAheadItems {
    using Index = uint32_t;
    static HMSM_HOST_DEVICE Index count(const gpu::PassConstants& pc) { return pc.element_count; }
    static HMSM_HOST_DEVICE void item(const BufferPointers& b, const gpu::PassConstants& pc, Index i) {
        const Element e = element_of(i, kTopPoses ? pc.level_count : pc.model_chain_count);
        if constexpr (kTopPoses) walk_top_pose(b, pc, e.instance, int32_t(e.index));
        else walk_ahead(b, pc, e.instance, int32_t(e.index));
    }
};

}  // namespace

cudaError_t launch_batch_compose(const BufferPointers& b, const BatchLaunch& batch, const BatchShape& shape,
                                 cudaStream_t stream) {
    constexpr unsigned kThreads = HMSM_WORKGROUP_SIZE;
    switch (shape.kind) {
        case HMSM_DISPATCH_POSE_WALK_FROM_RECORDS:
            return launch_batch_items<PoseWalkItems<true>, kThreads>(b, batch, shape, stream);
        case HMSM_DISPATCH_POSE_WALK: return launch_batch_items<PoseWalkItems<false>, kThreads>(b, batch, shape, stream);
        case HMSM_DISPATCH_WALK_TOP_POSES:
            return launch_batch_items<WalkAheadItems<true>, kThreads>(b, batch, shape, stream);
        case HMSM_DISPATCH_WALK_AHEAD: return launch_batch_items<WalkAheadItems<false>, kThreads>(b, batch, shape, stream);
        default: return launch_batch<compose_pass>(b, batch, shape, stream);
    }
}

void emulate_batch_compose(const BufferPointers& b, const BatchLaunch& batch, const BatchShape& shape) {
    switch (shape.kind) {
        case HMSM_DISPATCH_POSE_WALK_FROM_RECORDS: return emulate_batch_items<PoseWalkItems<true>>(b, batch, shape.threads);
        case HMSM_DISPATCH_POSE_WALK: return emulate_batch_items<PoseWalkItems<false>>(b, batch, shape.threads);
        case HMSM_DISPATCH_WALK_TOP_POSES: return emulate_batch_items<WalkAheadItems<true>>(b, batch, shape.threads);
        case HMSM_DISPATCH_WALK_AHEAD: return emulate_batch_items<WalkAheadItems<false>>(b, batch, shape.threads);
        default: return emulate_batch<compose_pass>(b, batch, shape);
    }
}

}  // namespace hmsm::detail::cuda
