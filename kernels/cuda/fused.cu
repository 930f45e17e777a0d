// Composition::fused: passes 1-5 in one launch, block k for group instance k (gpu_layout.h
// HMSM_MODE_FUSED; docs/architecture.md). An instance's passes read only its own chains and
// nodes, so __syncthreads() between two passes stands in for the launch boundary:
//   1+2. wind_force and integrate per chain (chain_math.cuh, the separate kernels' math);
//   3.   compose's pointer-jumping rounds, round r reading half HMSM_HALF_READ(r) and writing
//        half HMSM_HALF_WRITTEN(r), as pointer_jumping_in_dispatch;
//   4.   node_relative per node;
//   5.   root_positions' rounds, the last writing O and the joint matrices.
// Shared variant (kShared): the rounds' two halves live in dynamic shared memory, rotation half
// h of chain c at (h n + c) 9 floats; integrate puts T into the half round 0 reads. The last
// compose round also writes R to the pose half of chain_rotation, node_relative and the joint
// matrices read R from shared memory, and root_positions' two origin halves (3 floats per chain
// each) reuse the rotation half that is not the pose half. Only the pose halves reach device
// memory. Device variant: the rounds run in the ping-pong halves of device memory exactly as
// the in-dispatch compose and root_positions kernels do. shaders/glsl/fused.comp is the same.
#include "chain_math.cuh"

#include <vector>

namespace hmsm::detail::cuda {
namespace {

/// The shared-memory rounds of one instance (layout above).
struct Pool {
    float* p;
    uint32_t n;          // chains per instance
    uint32_t pose_half;  // the half the last round writes

    HMSM_HOST_DEVICE uint32_t rotation_at(uint32_t which, uint32_t c) const { return (which * n + c) * 9; }
    HMSM_HOST_DEVICE Mat3 rotation(uint32_t which, uint32_t c) const {
        const float* a = p + rotation_at(which, c);
        return {make_float3(a[0], a[1], a[2]), make_float3(a[3], a[4], a[5]), make_float3(a[6], a[7], a[8])};
    }
    HMSM_HOST_DEVICE void set_rotation(uint32_t which, uint32_t c, const Mat3& m) const {
        float* a = p + rotation_at(which, c);
        a[0] = m.c0.x, a[1] = m.c0.y, a[2] = m.c0.z;
        a[3] = m.c1.x, a[4] = m.c1.y, a[5] = m.c1.z;
        a[6] = m.c2.x, a[7] = m.c2.y, a[8] = m.c2.z;
    }
    /// Origin half `which` of chain c, in the rotation half other than the pose half.
    HMSM_HOST_DEVICE uint32_t origin_at(uint32_t which, uint32_t c) const {
        return rotation_at(1 - pose_half, 0) + (which * n + c) * 3;
    }
    HMSM_HOST_DEVICE float4 origin(uint32_t which, uint32_t c) const {
        const float* a = p + origin_at(which, c);
        return make_float4(a[0], a[1], a[2], 0.0f);
    }
    HMSM_HOST_DEVICE void set_origin(uint32_t which, uint32_t c, float4 o) const {
        float* a = p + origin_at(which, c);
        a[0] = o.x, a[1] = o.y, a[2] = o.z;
    }
};

/// Passes 1 and 2 for model chain c of group instance k. R and O of the previous step (the
/// pose half) are read with plain loads: this kernel writes them later.
template <bool kShared>
HMSM_HOST_DEVICE void fused_chain(const BufferPointers& b, const gpu::PassConstants& pc, uint32_t k,
                                  uint32_t c, const Pool& pool) {
    const uint64_t chain = state_chain(pc, k, int32_t(c));
    const uint64_t pose = half_begin(pc, pc.src_half) + chain;
    const float2 g = chain_wind_force(b, pc, k, c, xyz(b.chain_origin[pose]),
                                      load_mat3_written_in_block(b.chain_rotation, pose));
    b.chain_force[chain] = g;
    const Mat3 t = chain_integrate(b, pc, k, c, chain, g);
    store_mat3(b.chain_local, chain, t);
    if (kShared) pool.set_rotation(HMSM_HALF_READ(0u), c, t);
}

/// One compose round for model chain c; the last round leaves R in the pose half.
template <bool kShared>
HMSM_HOST_DEVICE void fused_compose(const BufferPointers& b, const gpu::PassConstants& pc, uint32_t k,
                                    uint32_t c, uint32_t round, const Pool& pool) {
    const uint32_t src = HMSM_HALF_READ(round), dst = HMSM_HALF_WRITTEN(round);
    if (!kShared) return compose_jump<true, true>(b, pc, k, c, round, src, dst);
    const int32_t ancestor =
        load(b.chain_jump + uint64_t(round) * pc.total_model_chains + pc.model_chain_begin + c);
    Mat3 r = pool.rotation(src, c);
    if (ancestor >= 0) r = pool.rotation(src, uint32_t(ancestor)) * r;
    pool.set_rotation(dst, c, r);
    if (round + 1 == pc.round) store_mat3(b.chain_rotation, half_begin(pc, dst) + state_chain(pc, k, int32_t(c)), r);
}

/// Pass 4 for model node `node`: u = R_owner l.
template <bool kShared>
HMSM_HOST_DEVICE void fused_node(const BufferPointers& b, const gpu::PassConstants& pc, uint32_t k,
                                 uint32_t node, const Pool& pool) {
    const uint32_t model_node = pc.model_node_begin + node;
    const int32_t owner = load(b.node_owner + model_node);
    const float3 local = xyz(load(b.node_local + model_node));
    const Mat3 r = kShared ? pool.rotation(pool.pose_half, uint32_t(owner))
                           : load_mat3_written_in_block(
                                 b.chain_rotation, half_begin(pc, pool.pose_half) + state_chain(pc, k, owner));
    b.node_relative[state_node(pc, k, int32_t(node))] = with_w(r * local, 0.0f);
}

/// One root_positions round for model chain c; the last writes O and the joint matrix.
template <bool kShared>
HMSM_HOST_DEVICE void fused_root(const BufferPointers& b, const gpu::PassConstants& pc, uint32_t k,
                                 uint32_t c, uint32_t round, const Pool& pool) {
    const uint32_t src = HMSM_HALF_READ(round), dst = HMSM_HALF_WRITTEN(round);
    const bool last = round + 1 == pc.round;
    if (!kShared) return root_jump<true, true>(b, pc, k, int32_t(c), round, src, dst, last);
    const int32_t ancestor =
        load(b.chain_jump + uint64_t(round) * pc.total_model_chains + pc.model_chain_begin + c);
    auto sum_so_far = [&](uint32_t chain) {
        return round == 0 ? own_offset<true>(b, pc, k, int32_t(chain)) : pool.origin(src, chain);
    };
    float4 origin = sum_so_far(c);
    if (ancestor >= 0) origin = origin + sum_so_far(uint32_t(ancestor));
    if (!last) return pool.set_origin(dst, c, origin);
    const uint64_t chain = state_chain(pc, k, int32_t(c));
    b.chain_origin[half_begin(pc, dst) + chain] = origin;
    store_joint_of(b, chain, pool.rotation(pool.pose_half, c), origin);
}

/// The passes of group instance k in order. each(count, f) calls f(i) for every i < count (a
/// block's threads striding on the device, a loop on the host); sync() separates two passes (and
/// two rounds), as __syncthreads() does on the device.
#pragma nv_exec_check_disable
template <bool kShared, class Each, class Sync>
HMSM_HOST_DEVICE void run_instance(const BufferPointers& b, const gpu::PassConstants& pc, uint32_t k,
                                   const Pool& pool, Each each, Sync sync) {
    const uint32_t n = pc.model_chain_count;
    each(n, [&](uint32_t c) { fused_chain<kShared>(b, pc, k, c, pool); });
    sync();
    for (uint32_t round = 0; round < pc.round; ++round) {
        each(n, [&](uint32_t c) { fused_compose<kShared>(b, pc, k, c, round, pool); });
        sync();
    }
    each(pc.model_node_count, [&](uint32_t node) { fused_node<kShared>(b, pc, k, node, pool); });
    sync();
    for (uint32_t round = 0; round < pc.round; ++round) {
        each(n, [&](uint32_t c) { fused_root<kShared>(b, pc, k, c, round, pool); });
        sync();  // also before the next instance of this block reuses the pool
    }
}

template <bool kShared>
__global__ void __launch_bounds__(HMSM_MAX_ROUNDS_WORKGROUP_SIZE)
    fused_kernel(const BufferPointers b, const gpu::PassConstants pc) {
    extern __shared__ float shared_pool[];
    begin_pass();
    const Pool pool{shared_pool, pc.model_chain_count, HMSM_FINAL_HALF(pc.round)};
    auto each = [](uint32_t count, auto f) {
        for (uint32_t i = threadIdx.x; i < count; i += blockDim.x) f(i);
    };
    auto sync = [] { __syncthreads(); };
    for (uint32_t k = blockIdx.x; k < dispatch_instances(pc); k += gridDim.x)
        if (!instance_paused(b, pc, k)) run_instance<kShared>(b, pc, k, pool, each, sync);  // uniform per block
}

/// Shared memory a block may have without opting in (cudaFuncAttributeMaxDynamicSharedMemorySize).
constexpr uint64_t kDefaultSharedBytes = 48 * 1024;

}  // namespace

cudaError_t launch_fused(const BufferPointers& b, const gpu::PassConstants& pc, cudaStream_t stream,
                         uint64_t shared_limit) {
    if (pc.element_count == 0) return cudaSuccess;
    const unsigned blocks = launch_blocks_per_instance(pc);
    const unsigned threads = gpu::rounds_workgroup_size(pc.model_chain_count);
    const uint64_t bytes = gpu::fused_shared_bytes(pc.model_chain_count);
    if (bytes > shared_limit) return launch_pass(fused_kernel<false>, blocks, threads, stream, b, pc);
    return launch_pass(fused_kernel<true>, blocks, threads, stream, b, pc, size_t(bytes));
}

cudaError_t allow_fused_shared(uint64_t shared_limit) {
    if (shared_limit <= kDefaultSharedBytes) return cudaSuccess;
    return cudaFuncSetAttribute(fused_kernel<true>, cudaFuncAttributeMaxDynamicSharedMemorySize, int(shared_limit));
}

void emulate_fused(const BufferPointers& b, const gpu::PassConstants& pc, uint64_t shared_limit) {
    if (pc.element_count == 0) return;
    const bool shared = gpu::fused_shared_bytes(pc.model_chain_count) <= shared_limit;
    std::vector<float> storage(shared ? size_t(pc.model_chain_count) * HMSM_FUSED_SHARED_FLOATS_PER_CHAIN : 0);
    const Pool pool{storage.data(), pc.model_chain_count, HMSM_FINAL_HALF(pc.round)};
    auto each = [](uint32_t count, auto f) {
        for (uint32_t i = 0; i < count; ++i) f(i);
    };
    auto sync = [] {};
    for (uint32_t k = 0; k < dispatch_instances(pc); ++k) {
        if (instance_paused(b, pc, k)) continue;
        if (shared) run_instance<true>(b, pc, k, pool, each, sync);
        else run_instance<false>(b, pc, k, pool, each, sync);
    }
}

}  // namespace hmsm::detail::cuda
