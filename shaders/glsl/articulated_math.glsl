// The coupled dynamics' articulated exchange (docs/model.md 3.13): pass 1's impulse of a chain's
// own wind and aerodynamic damping, and pass 2's sweeps over an instance (INSTANCE_SWEEP: one
// workgroup per instance, depth by depth with a barrier between depths). Mirrors
// src/common/articulated_math.h (the math of the CPU passes and the CUDA kernels) line by line;
// include after chain_math.glsl. Spatial vectors are 6 scalars in the chain's rest frame about
// its joint, angular part first; the record holds the per-step quotients folded on the host.
#ifndef HMSM_ARTICULATED_MATH_GLSL
#define HMSM_ARTICULATED_MATH_GLSL

/// Scalar i of model chain m's record (gpu_layout.h HMSM_CHAIN_ARTICULATED_VEC4S, by vec4, in
/// chain_dynamics' place).
float articulated_field(uint m, uint i) { return chain_dynamics[(i >> 2u) * pc.total_model_chains + m][i & 3u]; }

/// A chain's scratch of the step where integrate writes T (chain_local's columns 0 and 1:
/// gpu_layout.h): its impulse, then what the up sweep passes on.
vec4 kept_at(uint chain, uint column) { return chain_local[chain][column]; }
void store_kept(uint chain, vec4 low, vec4 high) {
    chain_local[chain][0] = low;
    chain_local[chain][1] = high;
}
/// A chain's spatial change of motion on the way down: its halves of chain_load, then
/// chain_force (gpu_layout.h).
void load_motion(uint chain, out float a[6]) {
    vec2 first = chain_load[chain], second = chain_load[half_offset(1u) + chain], third = chain_force[chain];
    a = float[6](first.x, first.y, second.x, second.y, third.x, third.y);
}
void store_motion(uint chain, float a[6]) {
    chain_load[chain] = vec2(a[0], a[1]);
    chain_load[half_offset(1u) + chain] = vec2(a[2], a[3]);
    chain_force[chain] = vec2(a[4], a[5]);
}

/// Pass 1 for model chain c (state chain `chain`) with the wind w in its previous-step frame:
/// the impulse over the step of its own wind (moment about the joint, force) and of its
/// aerodynamic damping per axis, I (1 - exp(-x)) V with x = aero dt / I (sqrt(|w|) + eta |V|),
/// where T goes.
void articulated_impulse(uint c, uint chain, vec3 w) {
    uint m = pc.model_chain_begin + c;
    vec3 moment = vec3(articulated_field(m, 28u), articulated_field(m, 29u), articulated_field(m, 30u));
    float area = articulated_field(m, 31u);
    vec2 rate = chain_state[chain].zw;
    float speed = sqrt(sqrt(w.x * w.x + w.y * w.y + w.z * w.z));
    float eta = articulated_field(m, 15u);
    vec2 damping;
    for (uint a = 0u; a < 2u; ++a) {
        float x = articulated_field(m, 40u + a) * (speed + eta * abs(rate[a]));
        float taken = x > 1e-4 ? 1.0 - exp(-x) : x * (1.0 - 0.5 * x);
        damping[a] = articulated_field(m, 38u + a) * taken * rate[a];
    }
    vec3 torque = vec3(moment.y * w.z - moment.z * w.y, moment.z * w.x - moment.x * w.z,
                       moment.x * w.y - moment.y * w.x);
    store_kept(chain, vec4(torque, area * w.x), vec4(area * w.y, area * w.z, damping));
}

/// The up sweep at model chain j of group instance k: with p the sum of its children's
/// passed-on forces minus its own wind impulse, the joint's free impulse u = b - S^T p, w = G u,
/// and the force it passes to its parent, X^T (p + U w), in the parent's frame; kept in its
/// scratch (column 0, column 1 xy) with w (column 1 zw).
void articulated_up_at(uint k, uint j) {
    uint m = pc.model_chain_begin + j;
    float p[6] = float[6](0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    uint first = uint(articulated_field(m, 42u)), last = first + uint(articulated_field(m, 43u));
    uint child = first;
    for (; child + 4u <= last; child += 4u) {  // four children's loads in flight together
        vec4 low[4], rest[4];
        for (uint c = 0u; c < 4u; ++c) {
            low[c] = kept_at(state_chain(k, child + c), 0u);
            rest[c] = kept_at(state_chain(k, child + c), 1u);
        }
        for (uint c = 0u; c < 4u; ++c) {
            p[0] += low[c].x; p[1] += low[c].y; p[2] += low[c].z; p[3] += low[c].w;
            p[4] += rest[c].x; p[5] += rest[c].y;
        }
    }
    for (; child < last; ++child) {
        uint at = state_chain(k, child);
        vec4 low = kept_at(at, 0u);
        vec2 rest = kept_at(at, 1u).xy;
        p[0] += low.x; p[1] += low.y; p[2] += low.z; p[3] += low.w; p[4] += rest.x; p[5] += rest.y;
    }
    uint chain = state_chain(k, j);
    vec4 s = chain_state[chain];
    vec4 low = kept_at(chain, 0u), high_half = kept_at(chain, 1u);
    float impulse[8] = float[8](low.x, low.y, low.z, low.w, high_half.x, high_half.y, high_half.z, high_half.w);
    for (int i = 0; i < 6; ++i) p[i] -= impulse[i];
    float u[2];
    for (uint a = 0u; a < 2u; ++a) {
        float b = -articulated_field(m, 32u + a) * s[a] - articulated_field(m, 34u + a) * s[2u + a] - impulse[6u + a];
        u[a] = b - p[2u * a];  // S^T p: the moment about the joint's x and z axes
    }
    vec2 w = vec2(articulated_field(m, 12u) * u[0] + articulated_field(m, 13u) * u[1],
                  articulated_field(m, 13u) * u[0] + articulated_field(m, 14u) * u[1]);
    float c[6];
    for (uint i = 0u; i < 6u; ++i) c[i] = p[i] + articulated_field(m, i) * w.x + articulated_field(m, 6u + i) * w.y;
    // X^T: n' = Q n + d x (Q f), f' = Q f; Q column j and d_j in scalars 16 + 4 j.
    vec3 qn = vec3(0.0), qf = vec3(0.0);
    for (uint r = 0u; r < 3u; ++r)
        for (uint col = 0u; col < 3u; ++col) {
            float q = articulated_field(m, 16u + 4u * col + r);
            qn[r] += q * c[col];
            qf[r] += q * c[3u + col];
        }
    vec3 d = vec3(articulated_field(m, 19u), articulated_field(m, 23u), articulated_field(m, 27u));
    vec3 n = vec3(qn.x + d.y * qf.z - d.z * qf.y, qn.y + d.z * qf.x - d.x * qf.z, qn.z + d.x * qf.y - d.y * qf.x);
    store_kept(chain, vec4(n, qf.x), vec4(qf.y, qf.z, w));
}

/// The down sweep at model chain j of group instance k: its joint's change of rate
/// dV = w - G U^T a' with a' = X a_parent (zero for the trunk), its own a = a' + S dV (kept in
/// chain_load and chain_force), then the joint's step S += dt V + theta dt dV, V += dV clamped at
/// max_angle, the fade and T.
void articulated_down_at(uint k, uint j) {
    uint m = pc.model_chain_begin + j;
    int parent = chain_parent[m];
    uint chain = state_chain(k, j);
    vec2 w = kept_at(chain, 1u).zw;
    float a[6] = float[6](0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    if (parent >= 0) {
        // X: omega = Q^T omega_p, v = Q^T (v_p + omega_p x d).
        float from_parent[6];
        load_motion(state_chain(k, uint(parent)), from_parent);
        vec3 omega_p = vec3(from_parent[0], from_parent[1], from_parent[2]);
        vec3 d = vec3(articulated_field(m, 19u), articulated_field(m, 23u), articulated_field(m, 27u));
        vec3 v = vec3(from_parent[3] + omega_p.y * d.z - omega_p.z * d.y,
                      from_parent[4] + omega_p.z * d.x - omega_p.x * d.z,
                      from_parent[5] + omega_p.x * d.y - omega_p.y * d.x);
        for (uint col = 0u; col < 3u; ++col) {
            float omega = 0.0, linear = 0.0;
            for (uint r = 0u; r < 3u; ++r) {
                float q = articulated_field(m, 16u + 4u * col + r);
                omega += q * omega_p[r];
                linear += q * v[r];
            }
            a[col] = omega;
            a[3u + col] = linear;
        }
    }
    vec2 ua = vec2(0.0);
    for (uint i = 0u; i < 6u; ++i) {
        ua.x += articulated_field(m, i) * a[i];
        ua.y += articulated_field(m, 6u + i) * a[i];
    }
    vec2 dv = vec2(w.x - (articulated_field(m, 12u) * ua.x + articulated_field(m, 13u) * ua.y),
                   w.y - (articulated_field(m, 13u) * ua.x + articulated_field(m, 14u) * ua.y));
    a[0] += dv.x;
    a[2] += dv.y;
    vec4 s = chain_state[chain];
    float dt = pc.params.x, max_angle = pc.params.y;
    for (uint axis = 0u; axis < 2u; ++axis) {
        s[axis] += dt * s[2u + axis] + articulated_field(m, 36u + axis) * dv[axis];
        s[2u + axis] += dv[axis];
        if (abs(s[axis]) > max_angle) {
            s[axis] = sign(s[axis]) * max_angle;
            s[2u + axis] = 0.0;
        }
    }
    s = faded_state(k, m, s);
    mat3 t = local_transform(k, m, parent < 0, s.xy);
    store_motion(chain, a);  // after every load, as in the CUDA kernel
    chain_state[chain] = s;
    chain_local[chain] = as_mat3x4(t);
}

/// Pass 2 for group instance k, every invocation of the workgroup on every
/// gl_WorkGroupSize.x-th chain of a depth: up from the deepest depth, then down from the trunk,
/// a barrier after each depth (the depths are ranges: the record's vec4 11).
void articulated_sweep(uint k) {
    uint depths = 11u * pc.total_model_chains + pc.model_chain_begin;
    for (uint end = pc.model_chain_count; end > 0u;) {
        uint begin = uint(chain_dynamics[depths + end - 1u].x);
        for (uint j = begin + gl_LocalInvocationID.x; j < end; j += gl_WorkGroupSize.x) articulated_up_at(k, j);
        memoryBarrierBuffer();
        barrier();
        end = begin;
    }
    for (uint begin = 0u; begin < pc.model_chain_count;) {
        uint end = uint(chain_dynamics[depths + begin].y);
        for (uint j = begin + gl_LocalInvocationID.x; j < end; j += gl_WorkGroupSize.x) articulated_down_at(k, j);
        memoryBarrierBuffer();
        barrier();
        begin = end;
    }
}

#endif  // HMSM_ARTICULATED_MATH_GLSL
