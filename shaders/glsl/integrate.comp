#version 450
// Pass 2: symplectic Euler on the two joint angles (theta_x, theta_z), clamped at max_angle,
// then the local transform T = Q Rz(theta_z) Rx(theta_x), with Ry(yaw) in front for the trunk
// (chain_math.glsl; src/cpu/integrate.cpp). INSTANCE_SWEEP (the articulated exchange): workgroup
// k sweeps group instance k (articulated_math.glsl).
#extension GL_GOOGLE_include_directive : require
#define HMSM_SPECIALIZED_WORKGROUP_SIZE
#define HMSM_SWEEP_COHERENCE coherent
#include "common.glsl"
#include "chain_math.glsl"
#include "articulated_math.glsl"

void main() {
    load_constants();
    if (pc.kind == HMSM_DISPATCH_INSTANCE_SWEEP) {
        uint k = rounds_instance();
        if (k >= pc.element_count / pc.model_chain_count || instance_paused(k)) return;  // uniform per workgroup
        articulated_sweep(k);
        return;
    }
    uint i = thread_index();
    if (i >= pc.element_count) return;
    uint k = i / pc.model_chain_count;
    if (instance_paused(k)) return;
    uint c = i % pc.model_chain_count;
    uint chain = state_chain(k, c);
    chain_local[chain] = as_mat3x4(chain_integrate(k, c, chain, chain_force[chain]));
}
