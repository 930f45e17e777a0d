// Pass 7: branch-mesh and leaf vertices rigid with their chain, v = O_c + R_c v_rest, normal
// R_c n_rest, the pose read from the joint matrix [R_c | O_c] (48 bytes, three loads). Base-ring
// vertices of child chains are the paper's contour fix-up: a blend (1 - beta) own + beta parent
// of the same rest vertex carried by the parent chain, normal renormalized, so the joint stays
// closed while the child swings. The outputs are written once,
// coalesced: 32 bytes per vertex (position and normal), or 16 in the packed vertex layout
// (HMSM_DISPATCH_CONTOUR_PACKED, gpu_layout.h), where the position's w carries the octahedral normal word
// (src/common/octahedral.h) and vertex_normal is not written.
//
// The largest pass. In the packed layout it has a kernel of its own instead of the skeleton's
// one-element-per-thread loop: a thread reads the model-scope inputs of one model vertex (its
// chains, rest position and normal; shared by all instances) once, into registers, and places
// that vertex in up to HMSM_PACKED_CONTOUR_INSTANCES (8) consecutive instances (gpu_layout.h;
// shaders/glsl/contour.comp does the same). Read per vertex of every instance, those inputs were
// most of the pass's L2 traffic (docs/cuda.md has the measurements). The separate layout keeps
// the skeleton. The host emulation runs the same code in the same mapping: per element for
// separate, per work item (contour_packed_item) for packed.
#include "pass_math.cuh"

#include "../../src/common/octahedral.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace hmsm::detail::cuda {
namespace {

/// The model-scope inputs of model vertex v of the dispatch's model that every vertex has (the
/// fix-up's parent copies are read by contour_vertex, for the vertices that have them).
struct ContourVertex {
    int2 chains;  // (own chain, fix-up parent chain or -1)
    float3 rest_position, rest_normal;
};

HMSM_HOST_DEVICE ContourVertex contour_inputs(const BufferPointers& b, const gpu::PassConstants& pc,
                                              uint32_t index) {
    const uint32_t v = pc.model_vertex_begin + index;
    return {load(b.vertex_chain + v), xyz(load(b.vertex_rest_position + v)), xyz(load(b.vertex_rest_normal + v))};
}

/// Model vertex `index` in group instance k, thread i = k n + index of the dispatch.
HMSM_HOST_DEVICE void contour_vertex(const BufferPointers& b, const gpu::PassConstants& pc,
                                     const ContourVertex& in, uint32_t index, uint32_t k, uint64_t i) {
    const Pose own = load_joint(b, state_chain(pc, k, in.chains.x));
    float3 position = own.origin + own.rotation * in.rest_position;
    float3 normal = own.rotation * in.rest_normal;
    if (in.chains.y >= 0) {
        const uint32_t v = pc.model_vertex_begin + index;
        const Pose parent = load_joint(b, state_chain(pc, k, in.chains.y));
        const float3 p = parent.origin + parent.rotation * xyz(load(b.vertex_parent_position + v));
        const float3 n = parent.rotation * xyz(load(b.vertex_parent_normal + v));
        const float beta = pc.params.z;
        position = (1.0f - beta) * position + beta * p;
        normal = (1.0f - beta) * normal + beta * n;
        normal = (1.0f / sqrtf(dot(normal, normal))) * normal;
    }
    const uint64_t out = pc.vertex_begin + i;
    if (pc.kind == HMSM_DISPATCH_CONTOUR_PACKED) {
        b.vertex_position[out] =
            with_w(position, packed_word_to_w<float>(encode_normal_word(normal.x, normal.y, normal.z)));
    } else {
        b.vertex_position[out] = with_w(position, 1.0f);
        b.vertex_normal[out] = with_w(normal, 0.0f);
    }
}

/// Thread i of the dispatch (the host emulation's order): one vertex of one instance.
HMSM_HOST_DEVICE void contour_element(const BufferPointers& b, const gpu::PassConstants& pc, uint32_t i) {
    const Element e = element_of(i, pc.model_vertex_count);
    if (instance_paused(b, pc, e.instance)) return;
    contour_vertex(b, pc, contour_inputs(b, pc, e.index), e.index, e.instance, i);
}

/// Work item w of a packed dispatch (gpu_layout.h HMSM_PACKED_CONTOUR_INSTANCES): model vertex
/// w % n, read once, placed in instances [s K, s K + K) of group s = w / n. v is fastest, so a
/// warp writes consecutive vertices of one instance at a time.
HMSM_HOST_DEVICE void contour_packed_item(const BufferPointers& b, const gpu::PassConstants& pc, uint64_t w) {
    constexpr uint32_t kGroup = HMSM_PACKED_CONTOUR_INSTANCES;
    const uint32_t per_instance = pc.model_vertex_count;
    const uint32_t instances = pc.element_count / per_instance;
    const uint32_t group = uint32_t(w / per_instance), index = uint32_t(w % per_instance);
    const ContourVertex in = contour_inputs(b, pc, index);
    const uint32_t first = group * kGroup;
    const uint32_t last = instances < first + kGroup ? instances : first + kGroup;
    for (uint32_t k = first; k < last; ++k)
        if (!instance_paused(b, pc, k)) contour_vertex(b, pc, in, index, k, uint64_t(k) * per_instance + index);
}

/// The packed layout's kernel: a grid-stride loop over the work items. (A template, as every
/// kernel here, so that its host stub is not a global symbol of hmsm.)
/// kMayPause: as pass_kernel's (pass_math.cuh constants_for), for every contour kernel here.
template <bool kMayPause>
__global__ void __launch_bounds__(HMSM_WORKGROUP_SIZE)
    contour_packed_kernel(const BufferPointers b, const gpu::PassConstants pc_in) {
    begin_pass();
    const gpu::PassConstants pc = constants_for<kMayPause>(pc_in);
    const uint64_t items = gpu::packed_contour_threads(pc);
    for (uint64_t w = blockIdx.x * uint64_t(blockDim.x) + threadIdx.x; w < items;
         w += uint64_t(gridDim.x) * blockDim.x)
        contour_packed_item(b, pc, w);
}

/// The separate layout's kernel: a grid-stride loop over the vertices, each thread's first
/// vertex's model-scope inputs read before it waits for the pass before (begin_pass's halves,
/// pass_math.cuh), so their latency overlaps that pass's end. (contour_element's work.)
template <unsigned kThreads, bool kMayPause>
__global__ void __launch_bounds__(kThreads)
    contour_separate_kernel(const BufferPointers b, const gpu::PassConstants pc_in) {
    let_next_pass_start();
    const gpu::PassConstants pc = constants_for<kMayPause>(pc_in);
    uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
    ContourVertex first{};
    if (i < pc.element_count) {
        const uint32_t index = i % pc.model_vertex_count;
        first = contour_inputs(b, pc, index);
        if (first.chains.y >= 0) {  // the fix-up's parent copies, read after the joints
            prefetch_l1(b.vertex_parent_position + pc.model_vertex_begin + index);
            prefetch_l1(b.vertex_parent_normal + pc.model_vertex_begin + index);
        }
    }
    wait_for_previous_pass();
    for (bool is_first = true; i < pc.element_count; i += gridDim.x * blockDim.x, is_first = false) {
        const Element e = element_of(i, pc.model_vertex_count);
        if (instance_paused(b, pc, e.instance)) continue;
        contour_vertex(b, pc, is_first ? first : contour_inputs(b, pc, e.index), e.index, e.instance, i);
    }
}

struct contour_pass {
    static constexpr bool kRounds = false;
    static constexpr bool kSweeps = false;
    HMSM_CUDA_PASS_ELEMENT(contour)
};

/// The packed layout's items in a batched launch (contour_packed_kernel's loop body).
struct PackedContourItems {
    using Index = uint64_t;
    static HMSM_HOST_DEVICE Index count(const gpu::PassConstants& pc) { return gpu::packed_contour_threads(pc); }
    static HMSM_HOST_DEVICE void item(const BufferPointers& b, const gpu::PassConstants& pc, Index w) {
        contour_packed_item(b, pc, w);
    }
};

/// Threads of a separate-layout contour block (launch_contour says why).
constexpr unsigned kSeparateThreads = 256;

}  // namespace

cudaError_t launch_contour(const BufferPointers& b, const gpu::PassConstants& pc, cudaStream_t stream) {
    if (pc.element_count == 0) return cudaSuccess;
    // Listed: one thread per vertex of each listed instance, in either layout (contour_element).
    if (pc.instance_list != 0) return launch_listed<ElementItems<contour_pass>, contour_pass>(b, pc, stream);
    const bool may_pause = pc.params.w != 0.0f;  // the kernel variant with the check
    if (pc.kind != HMSM_DISPATCH_CONTOUR_PACKED) {
        // Blocks of 256: a quarter of the blocks to schedule and drain (measured faster for one tree
        // and for forests: docs/benchmarks/history/2026-11-26-nvidia-h100-45f6584.md, analysis).
        constexpr unsigned kThreads = kSeparateThreads;
        auto* kernel = may_pause ? contour_separate_kernel<kThreads, true> : contour_separate_kernel<kThreads, false>;
        return launch_pass(kernel, launch_blocks(pc.element_count, kThreads), kThreads, stream, b, pc);
    }
    const uint64_t items = gpu::packed_contour_threads(pc);
    const uint32_t blocks = launch_blocks(uint32_t(std::min<uint64_t>(items, UINT32_MAX)));
    return launch_pass(may_pause ? contour_packed_kernel<true> : contour_packed_kernel<false>, blocks,
                       HMSM_WORKGROUP_SIZE, stream, b, pc);
}

/// The same work on the host, in the same order as the device's (a packed dispatch by its work
/// items, so the tests that emulate it check the mapping the GPU runs).
void emulate_contour(const BufferPointers& b, const gpu::PassConstants& pc) {
    if (pc.element_count == 0) return;
    if (pc.kind != HMSM_DISPATCH_CONTOUR_PACKED || pc.instance_list != 0) return emulate<contour_pass>(b, pc);
    for (uint64_t w = 0; w < gpu::packed_contour_threads(pc); ++w) contour_packed_item(b, pc, w);
}

/// A batch in either layout: the separate layout's items are contour_element, its kernel's
/// loop body (whose first-vertex prefetch only moves loads earlier), in blocks of 256 threads
/// (launch_plan.cpp plans them so).
cudaError_t launch_batch_contour(const BufferPointers& b, const BatchLaunch& batch, const BatchShape& shape,
                                 cudaStream_t stream) {
    if (shape.kind == HMSM_DISPATCH_CONTOUR_PACKED)
        return launch_batch_items<PackedContourItems, HMSM_WORKGROUP_SIZE>(b, batch, shape, stream);
    return launch_batch_items<ElementItems<contour_pass>, kSeparateThreads>(b, batch, shape, stream);
}

void emulate_batch_contour(const BufferPointers& b, const BatchLaunch& batch, const BatchShape& shape) {
    if (shape.kind == HMSM_DISPATCH_CONTOUR_PACKED) return emulate_batch_items<PackedContourItems>(b, batch, shape.threads);
    emulate_batch_items<ElementItems<contour_pass>>(b, batch, shape.threads);
}

}  // namespace hmsm::detail::cuda
