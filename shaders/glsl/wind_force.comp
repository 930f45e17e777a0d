#version 450
// Pass 1: generalized wind force per chain, g = A (w_loc.z, -w_loc.x), from the wind in the
// chain's previous-step frame w_loc = R^T w(t) (src/cpu/wind_force.cpp).
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

void main() {
    uint i = thread_index();
    if (i >= pc.element_count) return;
    uint k = i / pc.model_chain_count;
    uint c = i % pc.model_chain_count;
    uint chain = state_chain(k, c);
    // f*t + phi, both already reduced mod 2 (every profile has period 2).
    float x = pc.wind.w + instance_origin[pc.instance_begin + k].w;
    vec3 wind = pc.wind.xyz * wind_profile_y(pc.profile, x);
    vec3 wind_local = transpose(as_mat3(chain_rotation[half_offset(pc.src_half) + chain])) * wind;
    float area = chain_constants[pc.model_chain_begin + c].w;
    chain_force[chain] = vec2(area * wind_local.z, -area * wind_local.x);
}
