#version 450
// Pass 1: generalized wind force per chain, g = A (w_loc.z, -w_loc.x), from the wind in the
// chain's previous-step frame w_loc = R^T w with w = lambda_i s Y(tau + phi_i) d plus the force
// fields at the chain's previous origin (chain_math.glsl; src/cpu/wind_force.cpp).
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"
#include "chain_math.glsl"

void main() {
    uint i = thread_index();
    if (i >= pc.element_count) return;
    uint k = i / pc.model_chain_count;
    uint c = i % pc.model_chain_count;
    uint chain = state_chain(k, c);
    vec2 g = chain_wind_force(k, c, chain, pc.src_half);
    chain_force[chain] = g;
    // Path walk: integrate follows in the same dispatch (integrate.comp).
    if (pc.mode == HMSM_MODE_PATH_WALK) chain_local[chain] = as_mat3x4(chain_integrate(k, c, chain, g));
}
