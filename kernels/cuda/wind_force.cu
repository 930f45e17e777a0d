// Pass 1: generalized wind force per chain, g = A (w_loc.z, -w_loc.x) with w_loc = R^T w(t) in
// the chain's frame of the previous step (src half of chain_rotation). The wind phase
// x0 = f t mod 2 of the step arrives in pc.wind.w; each instance adds its own front phase.
#include "pass_math.cuh"

namespace hmsm::detail::cuda {

static HMSM_HOST_DEVICE void wind_force_element(const BufferPointers& b,
                                                const gpu::PassConstants& pc, uint32_t i) {
    const Element e = element_of(i, pc.model_chain_count);
    const uint64_t chain = pc.chain_begin + i;
    const float4 origin = load(b.instance_origin + pc.instance_begin + e.instance);
    const float x = pc.wind.w + origin.w;  // f t + phi, both reduced mod 2
    const float3 wind = wind_profile_y<float>(pc.profile, x) * make_float3(pc.wind.x, pc.wind.y, pc.wind.z);
    const Mat3 rotation = load_mat3(b.chain_rotation, half_begin(pc, pc.src_half) + chain);
    const float3 local = transpose_times(rotation, wind);
    const float area = load(b.chain_constants + pc.model_chain_begin + e.index).w;
    b.chain_force[chain] = make_float2(area * local.z, -area * local.x);
}

HMSM_CUDA_PASS(wind_force)

}  // namespace hmsm::detail::cuda
