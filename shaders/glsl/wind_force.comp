#version 450
// Pass 1: generalized wind force per chain, g = A (w_loc.z, -w_loc.x), from the wind in the
// chain's previous-step frame w_loc = R^T w with w = lambda_i s Y(tau + phi_i) d plus the force
// fields at the chain's previous origin (src/cpu/wind_force.cpp; table layout in gpu_layout.h).
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

void main() {
    uint i = thread_index();
    if (i >= pc.element_count) return;
    uint k = i / pc.model_chain_count;
    uint c = i % pc.model_chain_count;
    uint chain = state_chain(k, c);
    uint slot = HMSM_WIND_STEPS + HMSM_WIND_STEP_VEC4S * uint(pc.wind.w);
    uint instance = HMSM_INSTANCE_WIND_VEC4S * (pc.instance_begin + k);
    vec4 own = instance_wind[instance];  // (lambda, phi mod 2, 0, 0)
    float y;
    if (pc.profile == HMSM_WIND_PROFILE_TURBULENT) {
        // Yt = 1 + sum a_k cos(2 pi (frac(m_k tau + u_k) + frac(m_k phi))), reduced to [0, 1).
        y = 1.0;
        for (uint e = 0u; e < HMSM_WIND_MODE_VEC4S; ++e) {
            vec4 phase = wind_table[slot + 1u + e] + instance_wind[instance + 1u + e];
            phase -= floor(phase);
            vec4 a = wind_table[HMSM_WIND_AMPLITUDES + e];
            y += dot(a, cos(2.0 * HMSM_PI * phase));
        }
    } else {
        y = wind_profile_y(pc.profile, wind_table[slot].x + own.y);  // tau + phi, both mod 2
    }
    vec4 vector_count = wind_table[HMSM_WIND_VECTOR];  // (s d, number of fields)
    vec3 wind = own.x * y * vector_count.xyz;
    uint pose = half_offset(pc.src_half) + chain;
    vec3 x = chain_origin[pose].xyz;
    uint fields = uint(vector_count.w);
    for (uint f = 0u; f < fields; ++f) {
        vec4 sphere = wind_table[HMSM_WIND_FIELDS + 2u * f];
        vec4 force = wind_table[HMSM_WIND_FIELDS + 2u * f + 1u];
        vec3 offset = x - sphere.xyz;
        float distance = length(offset);
        float reach = max(0.0, 1.0 - distance / sphere.w);
        float h = reach * reach;
        if (force.w == 0.0) wind += h * force.xyz;
        else if (distance >= 1e-9) wind += (h * force.x / distance) * offset;
    }
    vec3 wind_local = transpose(as_mat3(chain_rotation[pose])) * wind;
    float area = chain_constants[pc.model_chain_begin + c].w;
    chain_force[chain] = vec2(area * wind_local.z, -area * wind_local.x);
}
