#version 450
// Pass 1: generalized wind force per chain, g = A (w_loc.z, -w_loc.x), from the wind in the
// chain's previous-step frame w_loc = R^T w with w = lambda_i s Y(tau + phi_i) d plus the force
// fields at the chain's previous origin (chain_math.glsl; src/cpu/wind_force.cpp); under the
// articulated exchange the chain's impulse, which integrate's sweeps take (articulated_math.glsl).
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"
#include "chain_math.glsl"
#include "articulated_math.glsl"

void main() {
    load_constants();
    uint i = thread_index();
    if (i >= pc.element_count) return;
    uint k = i / pc.model_chain_count;
    if (instance_paused(k)) return;
    uint c = i % pc.model_chain_count;
    uint chain = state_chain(k, c);
    if (pc.dynamics == HMSM_PASS_DYNAMICS_ARTICULATED) {  // alone or as a wind pair: pass 1 only
        vec3 x;
        mat3 rotation;
        if (pc.kind == HMSM_DISPATCH_WIND_PAIR) {
            mat3x4 j = joint_matrix[chain];
            x = joint_origin(j);
            rotation = joint_rotation(j);
        } else {
            uint pose = half_offset(pc.src_half) + chain;
            x = chain_origin[pose].xyz;
            rotation = as_mat3(chain_rotation[pose]);
        }
        articulated_impulse(c, chain, chain_local_wind(k, x, rotation));
        return;
    }
    // The wind pair (path walk): the previous pose is the joint matrix (the walk writes no R or O half), and
    // integrate's step follows in the same dispatch with g in hand; only the angles are stored
    // (the walk computes T from them; src/pass_table.h walk_reads, walk_writes).
    if (pc.kind == HMSM_DISPATCH_WIND_PAIR) {
        mat3x4 j = joint_matrix[chain];
        vec2 g = chain_wind_force(k, c, joint_origin(j), joint_rotation(j));
        chain_state[chain] = step_angles(k, pc.model_chain_begin + c, chain_state[chain], g);
        return;
    }
    uint pose = half_offset(pc.src_half) + chain;
    chain_force[chain] = chain_wind_force(k, c, chain_origin[pose].xyz, as_mat3(chain_rotation[pose]));
}
