// Pass 1: generalized wind force per chain, g = A (w_loc.z, -w_loc.x) with w_loc = R^T w in
// the chain's frame of the previous step (src half of chain_rotation), w = lambda_i s
// Y(tau + phi_i) d plus the force fields at the chain's previous origin. pc.wind.w is the
// step's slot of the wind table (gpu_layout.h), which holds tau and the turbulent phases
// reduced on the host.
#include "pass_math.cuh"

namespace hmsm::detail::cuda {

static HMSM_HOST_DEVICE void wind_force_element(const BufferPointers& b,
                                                const gpu::PassConstants& pc, uint32_t i) {
    const Element e = element_of(i, pc.model_chain_count);
    const uint64_t chain = pc.chain_begin + i;
    const float4* table = b.wind_table;
    const uint32_t slot = HMSM_WIND_STEPS + HMSM_WIND_STEP_VEC4S * uint32_t(pc.wind.w);
    const float4* instance = b.instance_wind + uint64_t(HMSM_INSTANCE_WIND_VEC4S) * (pc.instance_begin + e.instance);
    const float4 own = load(instance);  // (lambda, phi mod 2, 0, 0)
    float y;
    if (pc.profile == HMSM_WIND_PROFILE_TURBULENT)
        y = turbulent_y<float>(&table[HMSM_WIND_AMPLITUDES].x, &table[slot + 1].x, &instance[1].x);
    else
        y = wind_profile_y<float>(pc.profile, load(table + slot).x + own.y);  // tau + phi, both mod 2
    const float4 vector_count = load(table + HMSM_WIND_VECTOR);  // (s d, number of fields)
    float3 wind = (own.x * y) * xyz(vector_count);
    const uint64_t pose = half_begin(pc, pc.src_half) + chain;
    const float3 x = xyz(load(b.chain_origin + pose));
    const uint32_t fields = uint32_t(vector_count.w);
    for (uint32_t f = 0; f < fields; ++f) {
        const float4 sphere = load(table + HMSM_WIND_FIELDS + 2 * f);
        const float4 force = load(table + HMSM_WIND_FIELDS + 2 * f + 1);
        const float3 offset = make_float3(x.x - sphere.x, x.y - sphere.y, x.z - sphere.z);
        const float distance = sqrtf(dot(offset, offset));
        const float reach = fmaxf(0.0f, 1.0f - distance / sphere.w);
        const float h = reach * reach;
        if (force.w == 0.0f) wind = wind + h * xyz(force);
        else if (distance >= 1e-9f) wind = wind + (h * force.x / distance) * offset;
    }
    const Mat3 rotation = load_mat3(b.chain_rotation, pose);
    const float3 local = transpose_times(rotation, wind);
    const float area = load(b.chain_constants + pc.model_chain_begin + e.index).w;
    b.chain_force[chain] = make_float2(area * local.z, -area * local.x);
}

HMSM_CUDA_PASS(wind_force)

}  // namespace hmsm::detail::cuda
