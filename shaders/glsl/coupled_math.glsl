// The coupled dynamics of passes 1 and 2 (docs/model.md 3.13): the generalized force from the
// wind moment, the children's loads and the aerodynamic damping, and the exact step of the
// damped oscillator with the force held. Mirrors src/common/coupled_math.h (the math of the
// CPU passes and the CUDA kernels) line by line; include after common.glsl. The record holds the
// per-step quotients folded on the host: nothing here divides.
#ifndef HMSM_COUPLED_MATH_GLSL
#define HMSM_COUPLED_MATH_GLSL

/// vec4 `v` of model chain `model_chain`'s record (gpu_layout.h HMSM_CHAIN_DYNAMICS_VEC4S), stored
/// by vec4.
vec4 coupled_record(uint model_chain, uint v) { return chain_dynamics[v * pc.total_model_chains + model_chain]; }

/// The half of chain_load the step of wind-table slot pc.wind_slot writes; it reads the other
/// (gpu_layout.h).
uint load_half_written() { return uint(wind_table[HMSM_WIND_STEPS + HMSM_WIND_STEP_VEC4S * pc.wind_slot].y); }

/// Pass 1 of the coupled dynamics for model chain c of group instance k, with the wind w_local
/// in the chain's frame of the previous step; stores g as the chain's load in the half this step
/// writes, for its parent's next step.
vec2 coupled_force(uint k, uint c, vec3 w_local) {
    uint model_chain = pc.model_chain_begin + c;
    uint written = load_half_written();
    // Wind: the torque (q_ref M) x w_local about the joint, its x and z components.
    vec3 moment = coupled_record(model_chain, 4u).xyz;
    vec2 g = vec2(moment.y * w_local.z - moment.z * w_local.y, moment.x * w_local.y - moment.y * w_local.x);
    // Each child's load of the last step, rotated from the child's frame into this one by Q:
    // the passing vec4 of the child's record, (Q_00, Q_02, Q_20, Q_22).
    vec4 damping_children = coupled_record(model_chain, 3u);
    int first = int(damping_children.z), count = int(damping_children.w);
    for (int j = first; j < first + count; ++j) {
        vec2 load_j = chain_load[half_offset(1u - written) + state_chain(k, uint(j))];
        vec4 passing = coupled_record(pc.model_chain_begin + uint(j), HMSM_CHAIN_DYNAMICS_PASSING);
        g.x += passing.x * load_j.x + passing.y * load_j.y;
        g.y += passing.z * load_j.x + passing.w * load_j.y;
    }
    // Aerodynamic damping D_a = aero (sqrt(|w|) + eta |V_a|), the wind's and the motion's,
    // held as the torque that takes from the rate what exp(-x), x = D_a dt / I, would over one
    // step: (I / dt) (1 - exp(-x)) per unit rate.
    float speed = sqrt(sqrt(dot(w_local, w_local)));
    float motion_ratio = coupled_record(model_chain, 4u).w;
    vec4 s = chain_state[state_chain(k, c)];
    vec4 inertia_stiffness = coupled_record(model_chain, 2u);  // (I_x / dt, I_z / dt, 1 / K_x, 1 / K_z)
    for (int a = 0; a < 2; ++a) {
        float x = damping_children[a] * (speed + motion_ratio * abs(s[2 + a]));
        float taken = x > 1e-4 ? 1.0 - exp(-x) : x * (1.0 - 0.5 * x);
        g[a] -= inertia_stiffness[a] * taken * s[2 + a];
    }
    chain_load[half_offset(written) + state_chain(k, c)] = g;
    return g;
}

/// Pass 2 of the coupled dynamics: the exact step of static chain model_chain from state s under
/// g held, clamped at max_angle; returns the new state.
vec4 coupled_step(uint model_chain, vec4 s, vec2 g) {
    vec4 inertia_stiffness = coupled_record(model_chain, 2u);
    float max_angle = pc.params.y;
    for (int j = 0; j < 2; ++j) {
        // The offset from the equilibrium g/K turns by the transition of this axis.
        vec4 transition = coupled_record(model_chain, uint(j));
        float equilibrium = g[j] * inertia_stiffness[2 + j];
        float offset = s[j] - equilibrium;
        float next_rate = transition.z * offset + transition.w * s[2 + j];
        s[j] = equilibrium + transition.x * offset + transition.y * s[2 + j];
        s[2 + j] = next_rate;
        if (abs(s[j]) > max_angle) {
            s[j] = sign(s[j]) * max_angle;
            s[2 + j] = 0.0;
        }
    }
    return s;
}

#endif  // HMSM_COUPLED_MATH_GLSL
