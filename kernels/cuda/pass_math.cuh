// Shared by the seven pass kernels: programmatic dependent launch, the launch shapes, and the
// one kernel skeleton every pass fills (per element, in-dispatch rounds, instance sweeps, listed
// and batched launches) with its host emulation. The per-element vocabulary (loads, 3x3
// matrices, indexing) is device_math.cuh.
#pragma once

#include "device_math.cuh"

#include <cstdint>

namespace hmsm::detail::cuda {

/// begin_pass in its two halves, for a kernel that first reads static data (model and instance
/// buffers: uploaded with the scene, written by no pass), whose loads may then overlap the end
/// of the pass before: let_next_pass_start() first, then the static loads, then
/// wait_for_previous_pass() in every thread before any load of what a pass writes.
__device__ __forceinline__ void let_next_pass_start() {
#if defined(__CUDA_ARCH__) && __CUDA_ARCH__ >= 900
    asm volatile("griddepcontrol.launch_dependents;" ::: "memory");
#endif
}
__device__ __forceinline__ void wait_for_previous_pass() {
#if defined(__CUDA_ARCH__) && __CUDA_ARCH__ >= 900
    asm volatile("griddepcontrol.wait;" ::: "memory");
#endif
}

/// Programmatic dependent launch (compute capability 9.0 and later): every pass kernel starts
/// with this (or with its halves above). It lets the next pass's blocks be scheduled as soon as
/// all of this pass's blocks have started, then waits until the previous pass has completed and
/// its writes are visible — so each kernel boundary of a step costs less than a full launch. A
/// no-op on older GPUs and for kernels launched without the attribute (launch_pass).
__device__ __forceinline__ void begin_pass() {
    let_next_pass_start();
    wait_for_previous_pass();
}

/// Asks for the 128-byte line holding `p` in L1 without waiting for it (a hint).
__device__ __forceinline__ void prefetch_l1(const void* p) {
#ifdef __CUDA_ARCH__
    asm volatile("prefetch.global.L1 [%0];" ::"l"(p));
#endif
}

/// Launches a pass kernel on `stream` with programmatic stream serialization allowed (see
/// begin_pass); stream order and graph capture are otherwise as for <<<...>>>.
/// HMSM_CUDA_PROGRAMMATIC_LAUNCH=0 in the environment turns programmatic launch off (for
/// measuring what it brings); read once.
bool programmatic_launch_enabled();

/// `Params`: the kernel's second parameter, a dispatch's PassConstants or a batch's BatchLaunch.
template <class Kernel, class Params>
cudaError_t launch_pass(Kernel kernel, unsigned blocks, unsigned threads, cudaStream_t stream,
                        const BufferPointers& b, const Params& pc, size_t shared_bytes = 0) {
    if (!programmatic_launch_enabled()) {
        kernel<<<blocks, threads, shared_bytes, stream>>>(b, pc);
        return cudaGetLastError();
    }
    cudaLaunchAttribute attribute{};
    attribute.id = cudaLaunchAttributeProgrammaticStreamSerialization;
    attribute.val.programmaticStreamSerializationAllowed = 1;
    cudaLaunchConfig_t config{};
    config.gridDim = dim3(blocks);
    config.blockDim = dim3(threads);
    config.dynamicSmemBytes = shared_bytes;
    config.stream = stream;
    config.attrs = &attribute;
    config.numAttrs = 1;
    return cudaLaunchKernelEx(&config, kernel, b, pc);
}

/// Instances of a dispatch, for the one-block-per-instance in-dispatch rounds.
HMSM_HOST_DEVICE uint32_t dispatch_instances(const gpu::PassConstants& pc) {
    return pc.element_count / pc.model_chain_count;
}

/// Most blocks of a pass launch (HMSM_CUDA_MAX_BLOCKS in the environment overrides it, for
/// measurements; read once). Every kernel strides over the elements beyond its grid, so any
/// element count (10,000 instances x 78,563 vertices is 7.9e8) fits one launch. The cap is
/// 65,536 blocks (4.2M threads, a dozen waves on an H100): each block pays begin_pass() once,
/// and one block per 64 elements (up to 2^24 blocks) made the contour of 1,000 paper-1 trees
/// slower (measured: docs/benchmarks/history/2026-11-22-nvidia-h100-e7f0bd9.md, analysis, item 2).
uint32_t max_launch_blocks();

inline unsigned launch_blocks(uint32_t n, uint32_t threads = HMSM_WORKGROUP_SIZE) {
    const uint32_t max_blocks = max_launch_blocks();
    uint32_t blocks = uint32_t((uint64_t(n) + threads - 1) / threads);
    return blocks < max_blocks ? blocks : max_blocks;
}

/// Calls f(k) for group instances k = block, block + blocks, ... of a dispatch that one block
/// each takes, skipping paused ones (the whole block: its barriers stay uniform).
template <class F>
__device__ void for_each_block_instance(const BufferPointers& b, const gpu::PassConstants& pc, uint32_t block,
                                        uint32_t blocks, F&& f) {
    for (uint32_t k = block; k < dispatch_instances(pc); k += blocks)
        if (!instance_paused(b, pc, k)) f(k);
}

/// In-dispatch pointer jumping (compose, root_positions): block `block` of a grid of `blocks`
/// runs every round for group instance `block` (and block + blocks, ...), calling jump(k, chain,
/// round, src_half, dst_half) for each of the instance's chains, with __syncthreads() between
/// rounds.
template <class Jump>
__device__ void run_rounds_in_block(const BufferPointers& b, const gpu::PassConstants& pc, uint32_t block,
                                    uint32_t blocks, Jump jump) {
    for_each_block_instance(b, pc, block, blocks, [&](uint32_t k) {
        for (uint32_t round = 0; round < pc.round; ++round) {
            for (uint32_t c = threadIdx.x; c < pc.model_chain_count; c += blockDim.x)
                jump(k, c, round, HMSM_HALF_READ(round), HMSM_HALF_WRITTEN(round));
            __syncthreads();
        }
    });
}

/// The same on the host (emulate_NAME): round after round over every chain of every instance.
template <class Jump>
void emulate_rounds(const BufferPointers& b, const gpu::PassConstants& pc, Jump jump) {
    for (uint32_t round = 0; round < pc.round; ++round)
        for (uint32_t i = 0; i < pc.element_count; ++i) {
            const Element e = element_of(i, pc.model_chain_count);
            if (instance_paused(b, pc, e.instance)) continue;
            jump(e.instance, e.index, round, HMSM_HALF_READ(round), HMSM_HALF_WRITTEN(round));
        }
}

/// Blocks of an in-dispatch pointer-jumping launch: one per instance (kernels stride beyond).
inline unsigned launch_blocks_per_instance(const gpu::PassConstants& pc) {
    const uint32_t max_blocks = 1u << 24;
    const uint32_t instances = dispatch_instances(pc);
    return instances < max_blocks ? instances : max_blocks;
}

/// The one kernel skeleton every pass fills. A pass is a type P with
///   static HMSM_HOST_DEVICE void element(const BufferPointers&, const gpu::PassConstants&, uint32_t i)
/// (the work of thread i of the dispatch) and `static constexpr bool kRounds`; where kRounds
/// (compose, root_positions) also
///   template <bool kWrittenInBlock> static HMSM_HOST_DEVICE void jump(b, pc, k, c, round, src_half, dst_half)
/// (one pointer-jumping round for model chain c of group instance k; kWrittenInBlock: the src
/// half was written by this block's previous round). HMSM_CUDA_PASS / HMSM_CUDA_ROUNDS_PASS
/// below build P from NAME_element (and NAME_jump) and define launch_NAME and emulate_NAME.
/// One launcher adds a kernel of its own: contour's in the packed vertex layout (contour.cu),
/// which still fills P for the separate layout and the emulation.
/// kMayPause: the dispatch covers paused instances (PassConstants.params.w). Without, the kernel
/// hands on constants whose params.w is a literal 0, so instance_paused() folds to false and
/// the kernel carries no check at all (the launchers pick the variant).
template <bool kMayPause>
__device__ __forceinline__ gpu::PassConstants constants_for(const gpu::PassConstants& pc) {
    gpu::PassConstants constants = pc;
    if constexpr (!kMayPause) constants.params.w = 0.0f;
    return constants;
}

template <class P, unsigned kThreads = HMSM_WORKGROUP_SIZE, bool kMayPause = false>
static __global__ void __launch_bounds__(kThreads)
    pass_kernel(const BufferPointers b, const gpu::PassConstants pc_in) {
    begin_pass();
    const gpu::PassConstants pc = constants_for<kMayPause>(pc_in);
    for (uint32_t i = blockIdx.x * blockDim.x + threadIdx.x; i < pc.element_count;
         i += gridDim.x * blockDim.x)
        P::element(b, pc, i);
}

/// JUMP_ROUNDS_IN_DISPATCH: one block per instance runs every round (run_rounds_in_block).
template <class P, bool kMayPause = false>
static __global__ void __launch_bounds__(HMSM_MAX_ROUNDS_WORKGROUP_SIZE)
    rounds_kernel(const BufferPointers b, const gpu::PassConstants pc_in) {
    begin_pass();
    const gpu::PassConstants pc = constants_for<kMayPause>(pc_in);
    run_rounds_in_block(b, pc, blockIdx.x, gridDim.x,
                        [&](uint32_t k, uint32_t c, uint32_t round, uint32_t src, uint32_t dst) {
                            P::template jump<true>(b, pc, k, c, round, src, dst);
                        });
}

/// INSTANCE_SWEEP: one block per instance (gpu::sweep_workgroup_size threads) runs P::sweep
/// over its threads (the articulated exchange's integrate, articulated_math.cuh).
template <class P, bool kMayPause = false>
static __global__ void __launch_bounds__(HMSM_MAX_SWEEP_WORKGROUP_SIZE)
    sweep_kernel(const BufferPointers b, const gpu::PassConstants pc_in) {
    begin_pass();
    const gpu::PassConstants pc = constants_for<kMayPause>(pc_in);
    for_each_block_instance(b, pc, blockIdx.x, gridDim.x,
                            [&](uint32_t k) { P::sweep(b, pc, k, threadIdx.x, blockDim.x); });
}

/// The items of a per-element dispatch: element i runs P::element.
template <class P>
struct ElementItems {
    using Index = uint32_t;
    static HMSM_HOST_DEVICE Index count(const gpu::PassConstants& pc) { return pc.element_count; }
    static HMSM_HOST_DEVICE void item(const BufferPointers& b, const gpu::PassConstants& pc, Index i) {
        P::element(b, pc, i);
    }
};

/// A listed dispatch (gpu_layout.h PassConstants.instance_list): thread t runs item
/// t % listed_threads of listed instance t / listed_threads with the constants rebased to that
/// instance (element_index.h listed_instance_constants), as a dispatch over it alone would.
/// `Items` as for the batched launches below (ElementItems: P::element).
template <class Items>
static __global__ void __launch_bounds__(HMSM_WORKGROUP_SIZE)
    listed_kernel(const BufferPointers b, const gpu::PassConstants pc) {
    begin_pass();
    for (uint32_t t = blockIdx.x * blockDim.x + threadIdx.x; t < pc.element_count; t += gridDim.x * blockDim.x) {
        const uint32_t k = t / pc.listed_threads;
        const gpu::PassConstants one = listed_instance_constants(pc, load(b.instance_table + pc.instance_begin + k));
        Items::item(b, one, t - k * pc.listed_threads);
    }
}

/// Block k of a listed dispatch that takes a block per instance calls f with the constants of a
/// dispatch over listed instance k alone (and k + gridDim.x, ...; a list holds no paused one).
template <class F>
__device__ void for_each_listed_instance(const BufferPointers& b, const gpu::PassConstants& pc, F&& f) {
    for (uint32_t k = blockIdx.x; k < dispatch_instances(pc); k += gridDim.x)
        f(listed_instance_constants(pc, load(b.instance_table + pc.instance_begin + k)));
}

/// JUMP_ROUNDS_IN_DISPATCH of a listed dispatch: block k runs every round for listed instance k,
/// as rounds_kernel for a dispatch over that instance alone.
template <class P>
static __global__ void __launch_bounds__(HMSM_MAX_ROUNDS_WORKGROUP_SIZE)
    listed_rounds_kernel(const BufferPointers b, const gpu::PassConstants pc) {
    begin_pass();
    for_each_listed_instance(b, pc, [&](const gpu::PassConstants& one) {
        run_rounds_in_block(b, one, 0, 1,
                            [&](uint32_t instance, uint32_t c, uint32_t round, uint32_t src, uint32_t dst) {
                                P::template jump<true>(b, one, instance, c, round, src, dst);
                            });
    });
}

/// INSTANCE_SWEEP of a listed dispatch: block k sweeps listed instance k.
template <class P>
static __global__ void __launch_bounds__(HMSM_MAX_SWEEP_WORKGROUP_SIZE)
    listed_sweep_kernel(const BufferPointers b, const gpu::PassConstants pc) {
    begin_pass();
    for_each_listed_instance(b, pc,
                             [&](const gpu::PassConstants& one) { P::sweep(b, one, 0, threadIdx.x, blockDim.x); });
}

/// Launches a listed dispatch of pass P (in-dispatch rounds and sweeps: one block per listed instance),
/// `Items` the work of one thread of an instance.
template <class Items, class P>
cudaError_t launch_listed(const BufferPointers& b, const gpu::PassConstants& pc, cudaStream_t stream) {
    if constexpr (P::kRounds) {
        if (pc.kind == HMSM_DISPATCH_JUMP_ROUNDS_IN_DISPATCH)
            return launch_pass(listed_rounds_kernel<P>, launch_blocks_per_instance(pc),
                               gpu::rounds_workgroup_size(pc.model_chain_count), stream, b, pc);
    }
    if constexpr (P::kSweeps) {
        if (pc.kind == HMSM_DISPATCH_INSTANCE_SWEEP)
            return launch_pass(listed_sweep_kernel<P>, launch_blocks_per_instance(pc),
                               gpu::sweep_workgroup_size(dispatch_instances(pc), pc.model_chain_count), stream, b, pc);
    }
    return launch_pass(listed_kernel<Items>, launch_blocks(pc.element_count), HMSM_WORKGROUP_SIZE, stream, b, pc);
}

/// launch_NAME: an empty dispatch launches nothing; in-dispatch rounds take one block per
/// instance of rounds_workgroup_size threads, everything else blocks of HMSM_WORKGROUP_SIZE
/// up to the grid cap (launch_blocks).
template <class P>
cudaError_t launch(const BufferPointers& b, const gpu::PassConstants& pc, cudaStream_t stream) {
    if (pc.element_count == 0) return cudaSuccess;
    if (pc.instance_list != 0) return launch_listed<ElementItems<P>, P>(b, pc, stream);
    const bool may_pause = pc.params.w != 0.0f;
    if constexpr (P::kRounds) {
        if (pc.kind == HMSM_DISPATCH_JUMP_ROUNDS_IN_DISPATCH)
            return launch_pass(may_pause ? rounds_kernel<P, true> : rounds_kernel<P, false>,
                               launch_blocks_per_instance(pc), gpu::rounds_workgroup_size(pc.model_chain_count),
                               stream, b, pc);
    }
    if constexpr (P::kSweeps) {
        if (pc.kind == HMSM_DISPATCH_INSTANCE_SWEEP)
            return launch_pass(may_pause ? sweep_kernel<P, true> : sweep_kernel<P, false>,
                               launch_blocks_per_instance(pc),
                               gpu::sweep_workgroup_size(dispatch_instances(pc), pc.model_chain_count), stream, b, pc);
    }
    constexpr unsigned kThreads = HMSM_WORKGROUP_SIZE;
    return launch_pass(may_pause ? pass_kernel<P, kThreads, true> : pass_kernel<P, kThreads, false>,
                       launch_blocks(pc.element_count), kThreads, stream, b, pc);
}

/// emulate_NAME: the same element (or round) code, serially on the host.
template <class P>
void emulate(const BufferPointers& b, const gpu::PassConstants& pc) {
    if (pc.instance_list != 0) {  // instance after instance, each as a dispatch over it alone
        for (uint32_t k = 0; k < pc.element_count / pc.listed_threads; ++k)
            emulate<P>(b, listed_instance_constants(pc, b.instance_table[pc.instance_begin + k]));
        return;
    }
    if constexpr (P::kRounds) {
        if (pc.kind == HMSM_DISPATCH_JUMP_ROUNDS_IN_DISPATCH) {
            emulate_rounds(b, pc, [&](uint32_t k, uint32_t c, uint32_t round, uint32_t src, uint32_t dst) {
                P::template jump<false>(b, pc, k, c, round, src, dst);
            });
            return;
        }
    }
    if constexpr (P::kSweeps) {
        if (pc.kind == HMSM_DISPATCH_INSTANCE_SWEEP) {
            for (uint32_t k = 0; k < dispatch_instances(pc); ++k)
                if (!instance_paused(b, pc, k)) P::sweep(b, pc, k, 0, 1);
            return;
        }
    }
    for (uint32_t i = 0; i < pc.element_count; ++i) P::element(b, pc, i);
}

// --- batched launches (src/common/batch_index.h) ----------------------------------------
// A run of dispatches over different groups in one launch: block blockIdx.x finds its entry,
// loads the entry's constants (static during the step: read before begin_pass's wait) and runs
// the loop of the entry's own launch as block `block` of a grid of `blocks`: the same thread ->
// item mapping, the same per-item code, so every result is bit for bit the single launch's.
// The work of a dispatch is a count of items and the code of item i (Items::count, Items::item;
// Items::Index the loop's index type, as in the kernel of the dispatch's own launch).


/// kMayPause: some entry covers paused instances; each entry keeps its own params.w, so an
/// entry without paused instances skips none, as in its own launch.
template <class Items, unsigned kThreads, bool kMayPause>
static __global__ void __launch_bounds__(kThreads)
    batch_kernel(const BufferPointers b, const BatchLaunch batch) {
    const BatchBlock block = batch_block(batch.block_begin, batch.entries, blockIdx.x);
    const gpu::PassConstants pc = constants_for<kMayPause>(batch_constants(batch, block.entry));
    begin_pass();
    using Index = typename Items::Index;
    const Index count = Items::count(pc);
    for (Index i = Index(block.block) * blockDim.x + threadIdx.x; i < count; i += Index(block.blocks) * blockDim.x)
        Items::item(b, pc, i);
}

/// JUMP_ROUNDS_IN_DISPATCH entries, one block per instance (blocks of the launch's size, the
/// rounds_workgroup_size every entry of the launch shares: launch_plan.cpp).
template <class P, bool kMayPause>
static __global__ void __launch_bounds__(HMSM_MAX_ROUNDS_WORKGROUP_SIZE)
    batch_rounds_kernel(const BufferPointers b, const BatchLaunch batch) {
    const BatchBlock block = batch_block(batch.block_begin, batch.entries, blockIdx.x);
    const gpu::PassConstants pc = constants_for<kMayPause>(batch_constants(batch, block.entry));
    begin_pass();
    run_rounds_in_block(b, pc, block.block, block.blocks,
                        [&](uint32_t k, uint32_t c, uint32_t round, uint32_t src, uint32_t dst) {
                            P::template jump<true>(b, pc, k, c, round, src, dst);
                        });
}

/// INSTANCE_SWEEP entries, one block per instance.
template <class P, bool kMayPause>
static __global__ void __launch_bounds__(HMSM_MAX_SWEEP_WORKGROUP_SIZE)
    batch_sweep_kernel(const BufferPointers b, const BatchLaunch batch) {
    const BatchBlock block = batch_block(batch.block_begin, batch.entries, blockIdx.x);
    const gpu::PassConstants pc = constants_for<kMayPause>(batch_constants(batch, block.entry));
    begin_pass();
    for_each_block_instance(b, pc, block.block, block.blocks,
                            [&](uint32_t k) { P::sweep(b, pc, k, threadIdx.x, blockDim.x); });
}

template <class Items, unsigned kThreads>
cudaError_t launch_batch_items(const BufferPointers& b, const BatchLaunch& batch, const BatchShape& shape,
                               cudaStream_t stream) {
    if (shape.blocks == 0) return cudaSuccess;
    return launch_pass(shape.may_pause ? batch_kernel<Items, kThreads, true> : batch_kernel<Items, kThreads, false>,
                       shape.blocks, kThreads, stream, b, batch);
}

/// The same on the host: block after block, thread after thread, through the same entry search.
template <class Items>
void emulate_batch_items(const BufferPointers& b, const BatchLaunch& batch, uint32_t threads) {
    using Index = typename Items::Index;
    for (uint32_t g = 0; g < batch.block_begin[batch.entries]; ++g) {
        const BatchBlock block = batch_block(batch.block_begin, batch.entries, g);
        const gpu::PassConstants pc = batch_constants(batch, block.entry);
        for (uint32_t t = 0; t < threads; ++t)
            for (Index i = Index(block.block) * threads + t; i < Items::count(pc); i += Index(block.blocks) * threads)
                Items::item(b, pc, i);
    }
}

/// launch_batch_NAME: in-dispatch rounds take the rounds kernel, everything else per-element
/// blocks of HMSM_WORKGROUP_SIZE.
template <class P>
cudaError_t launch_batch(const BufferPointers& b, const BatchLaunch& batch, const BatchShape& shape,
                         cudaStream_t stream) {
    if constexpr (P::kRounds) {
        if (shape.kind == HMSM_DISPATCH_JUMP_ROUNDS_IN_DISPATCH) {
            if (shape.blocks == 0) return cudaSuccess;
            return launch_pass(shape.may_pause ? batch_rounds_kernel<P, true> : batch_rounds_kernel<P, false>,
                               shape.blocks, shape.threads, stream, b, batch);
        }
    }
    if constexpr (P::kSweeps) {
        if (shape.kind == HMSM_DISPATCH_INSTANCE_SWEEP) {
            if (shape.blocks == 0) return cudaSuccess;
            return launch_pass(shape.may_pause ? batch_sweep_kernel<P, true> : batch_sweep_kernel<P, false>,
                               shape.blocks, shape.threads, stream, b, batch);
        }
    }
    return launch_batch_items<ElementItems<P>, HMSM_WORKGROUP_SIZE>(b, batch, shape, stream);
}

template <class P>
void emulate_batch(const BufferPointers& b, const BatchLaunch& batch, const BatchShape& shape) {
    if constexpr (P::kRounds) {
        if (shape.kind == HMSM_DISPATCH_JUMP_ROUNDS_IN_DISPATCH) {
            for (uint32_t g = 0; g < batch.block_begin[batch.entries]; ++g) {
                const BatchBlock block = batch_block(batch.block_begin, batch.entries, g);
                const gpu::PassConstants pc = batch_constants(batch, block.entry);
                for (uint32_t k = block.block; k < dispatch_instances(pc); k += block.blocks) {
                    if (instance_paused(b, pc, k)) continue;
                    for (uint32_t round = 0; round < pc.round; ++round)
                        for (uint32_t c = 0; c < pc.model_chain_count; ++c)
                            P::template jump<false>(b, pc, k, c, round, HMSM_HALF_READ(round), HMSM_HALF_WRITTEN(round));
                }
            }
            return;
        }
    }
    if constexpr (P::kSweeps) {
        if (shape.kind == HMSM_DISPATCH_INSTANCE_SWEEP) {
            for (uint32_t g = 0; g < batch.block_begin[batch.entries]; ++g) {
                const BatchBlock block = batch_block(batch.block_begin, batch.entries, g);
                const gpu::PassConstants pc = batch_constants(batch, block.entry);
                for (uint32_t k = block.block; k < dispatch_instances(pc); k += block.blocks)
                    if (!instance_paused(b, pc, k)) P::sweep(b, pc, k, 0, 1);
            }
            return;
        }
    }
    emulate_batch_items<ElementItems<P>>(b, batch, shape.threads);
}

#define HMSM_CUDA_PASS_ELEMENT(name)                                                             \
    static HMSM_HOST_DEVICE void element(const BufferPointers& b, const gpu::PassConstants& pc, \
                                         uint32_t i) {                                           \
        name##_element(b, pc, i);                                                                \
    }
#define HMSM_CUDA_PASS_ENTRY_POINTS(name)                                                        \
    cudaError_t launch_##name(const BufferPointers& b, const gpu::PassConstants& pc,             \
                              cudaStream_t stream) {                                             \
        return launch<name##_pass>(b, pc, stream);                                               \
    }                                                                                            \
    void emulate_##name(const BufferPointers& b, const gpu::PassConstants& pc) {                 \
        emulate<name##_pass>(b, pc);                                                             \
    }                                                                                            \
    cudaError_t launch_batch_##name(const BufferPointers& b, const BatchLaunch& batch,           \
                                    const BatchShape& shape, cudaStream_t stream) {              \
        return launch_batch<name##_pass>(b, batch, shape, stream);                               \
    }                                                                                            \
    void emulate_batch_##name(const BufferPointers& b, const BatchLaunch& batch, const BatchShape& shape) { \
        emulate_batch<name##_pass>(b, batch, shape);                                             \
    }

/// The last line of a pass file whose threads each handle one element: NAME_element is all
/// the pass supplies.
#define HMSM_CUDA_PASS(name)                   \
    struct name##_pass {                       \
        static constexpr bool kRounds = false; \
        static constexpr bool kSweeps = false; \
        HMSM_CUDA_PASS_ELEMENT(name)           \
    };                                         \
    HMSM_CUDA_PASS_ENTRY_POINTS(name)

/// The same for a pass whose INSTANCE_SWEEP dispatches sweep instances: NAME_element and
/// NAME_sweep(b, pc, k, lane, lanes) (group instance k by lane `lane` of `lanes`).
#define HMSM_CUDA_SWEEP_PASS(name)                                                               \
    struct name##_pass {                                                                         \
        static constexpr bool kRounds = false;                                                   \
        static constexpr bool kSweeps = true;                                                    \
        HMSM_CUDA_PASS_ELEMENT(name)                                                             \
        static HMSM_HOST_DEVICE void sweep(const BufferPointers& b, const gpu::PassConstants& pc, \
                                           uint32_t k, uint32_t lane, uint32_t lanes) {          \
            name##_sweep(b, pc, k, lane, lanes);                                                 \
        }                                                                                        \
    };                                                                                           \
    HMSM_CUDA_PASS_ENTRY_POINTS(name)

/// The same for a pointer-jumping pass: NAME_element and NAME_jump<kWrittenInBlock>.
/// HMSM_CUDA_ROUNDS_PASS_TYPE alone defines the pass type, for a file whose launcher adds a
/// kernel of its own (compose.cu, for the path walk).
#define HMSM_CUDA_ROUNDS_PASS(name)  \
    HMSM_CUDA_ROUNDS_PASS_TYPE(name) \
    HMSM_CUDA_PASS_ENTRY_POINTS(name)
#define HMSM_CUDA_ROUNDS_PASS_TYPE(name)                                                       \
    struct name##_pass {                                                                       \
        static constexpr bool kRounds = true;                                                  \
        static constexpr bool kSweeps = false;                                                 \
        HMSM_CUDA_PASS_ELEMENT(name)                                                           \
        template <bool kWrittenInBlock>                                                        \
        static HMSM_HOST_DEVICE void jump(const BufferPointers& b, const gpu::PassConstants& pc, \
                                          uint32_t k, uint32_t c, uint32_t round,              \
                                          uint32_t src_half, uint32_t dst_half) {              \
            name##_jump<kWrittenInBlock>(b, pc, k, c, round, src_half, dst_half);              \
        }                                                                                      \
    };

}  // namespace hmsm::detail::cuda
