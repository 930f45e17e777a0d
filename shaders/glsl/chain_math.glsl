// The per-chain math of passes 1, 2, 3 and 5, written once for the separate pass shaders
// (wind_force.comp, integrate.comp, compose.comp, root_positions.comp) and the path walk
// (compose.comp, Composition::path_walk).
// Mirrors src/cpu/NAME.cpp; include after common.glsl.
#ifndef HMSM_CHAIN_MATH_GLSL
#define HMSM_CHAIN_MATH_GLSL

#include "coupled_math.glsl"

/// The wind of group instance k in a chain's previous-step frame, w_loc = R^T w,
/// w = lambda_i s Y(tau + phi_i) d (atmospheric: lambda_i s (e_x (1 + u') + e_y v' + e_z w'))
/// plus the force fields at the chain's previous origin x, R the chain's previous rotation
/// (docs/model.md 3.5, 3.7, 3.9; table in gpu_layout.h).
vec3 chain_local_wind(uint k, vec3 x, mat3 rotation) {
    uint slot = HMSM_WIND_STEPS + HMSM_WIND_STEP_VEC4S * pc.wind_slot;
    uint instance = HMSM_INSTANCE_WIND_VEC4S * (pc.instance_begin + k);
    vec4 own = instance_wind[instance];  // (lambda, phi mod 2, 0, 0)
    vec4 vector_count = wind_table[HMSM_WIND_VECTOR];  // (s d, number of fields)
    vec3 wind;
    if (pc.profile == HMSM_WIND_PROFILE_ATMOSPHERIC) {
        // w = lambda s (e_x (1 + u') + e_y v' + e_z w'): each component sums its modes'
        // a_k cos(2 pi (frac(kx_k tau + u_k) + spatial phase_k)), reduced to [0, 1).
        vec3 sums = vec3(1.0, 0.0, 0.0);
        for (uint e = 0u; e < HMSM_WIND_MODE_VEC4S; ++e) {
            vec4 phase = wind_table[slot + 1u + e] + instance_wind[instance + 1u + e];
            phase -= floor(phase);
            float part = dot(wind_table[HMSM_WIND_AMPLITUDES + e], cos(2.0 * HMSM_PI * phase));
            if (e < HMSM_WIND_MODES_U_VEC4S) sums.x += part;
            else if (e < HMSM_WIND_MODES_U_VEC4S + HMSM_WIND_MODES_V_VEC4S) sums.y += part;
            else sums.z += part;
        }
        wind = own.x * (sums.x * vector_count.xyz + sums.y * wind_table[HMSM_WIND_LATERAL].xyz +
                        sums.z * wind_table[HMSM_WIND_VERTICAL].xyz);
    } else {
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
        wind = own.x * y * vector_count.xyz;
    }
    uint fields = uint(vector_count.w);
    for (uint f = 0u; f < fields; ++f) {
        vec4 sphere = wind_table[HMSM_WIND_FIELDS + 2u * f];
        vec4 force = wind_table[HMSM_WIND_FIELDS + 2u * f + 1u];
        vec3 offset = x - sphere.xyz;
        float distance = length(offset);
        float reach = max(0.0, 1.0 - distance / sphere.w);
        if (!(reach > 0.0)) continue;  // outside the sphere: no contribution at all (never 0 * F)
        float h = reach * reach;
        if (force.w == 0.0) wind += h * force.xyz;
        else if (distance >= 1e-9) wind += (h * force.x / distance) * offset;
    }
    return transpose(rotation) * wind;
}

/// Pass 1 for model chain c of group instance k: the generalized force g = A (w_loc.z, -w_loc.x)
/// from the wind in its previous-step frame (chain_local_wind); under the coupled dynamics
/// coupled_force's g.
vec2 chain_wind_force(uint k, uint c, vec3 x, mat3 rotation) {
    vec3 wind_local = chain_local_wind(k, x, rotation);
    if (pc.dynamics == HMSM_PASS_DYNAMICS_COUPLED) return coupled_force(k, c, wind_local);  // docs/model.md 3.13
    float area = chain_constants[pc.model_chain_begin + c].w;
    return vec2(area * wind_local.z, -area * wind_local.x);
}

/// Pass 2, the step: symplectic Euler on the two joint angles (theta_x, theta_z) of static chain
/// model_chain from state s = (angles, rates) under generalized force g, clamped at max_angle;
/// returns the new state.
vec4 integrate_step(uint model_chain, vec4 s, vec2 g) {
    vec4 constants = chain_constants[model_chain];  // (I, K, D, A)
    float dt = pc.params.x;
    float max_angle = pc.params.y;
    vec2 angle = s.xy;
    vec2 rate = s.zw;
    vec2 force = g - constants.y * angle - constants.z * rate;
    rate += dt / constants.x * force;
    angle += dt * rate;
    for (int j = 0; j < 2; ++j) {
        if (abs(angle[j]) > max_angle) {
            angle[j] = sign(angle[j]) * max_angle;
            rate[j] = 0.0;
        }
    }
    return vec4(angle, rate);
}

/// Pass 2, the transform: T = Q Rz(theta_z) Rx(theta_x) of static chain model_chain at `angle`,
/// with Ry(yaw) of group instance k in front for the trunk (`trunk`: it has no parent).
mat3 local_transform(uint k, uint model_chain, bool trunk, vec2 angle) {
    float cx = cos(angle.x), sx = sin(angle.x);
    float cz = cos(angle.y), sz = sin(angle.y);
    mat3 rx = mat3(vec3(1, 0, 0), vec3(0, cx, sx), vec3(0, -sx, cx));  // columns
    mat3 rz = mat3(vec3(cz, sz, 0), vec3(-sz, cz, 0), vec3(0, 0, 1));
    mat3 t = as_mat3(chain_rest_rotation[model_chain]) * rz * rx;
    if (trunk) {
        vec4 yaw = instance_yaw[pc.instance_begin + k];  // (cos, sin)
        mat3 ry = mat3(vec3(yaw.x, 0, -yaw.y), vec3(0, 1, 0), vec3(yaw.y, 0, yaw.x));
        t = ry * t;
    }
    return t;
}

/// The fade of group instance k (docs/model.md 3.12, fading to a coarser level): the state s a
/// step computed for static chain model_chain, times the step's factor sigma where the instance
/// fades to a level that folds the chain; else s as it is. Mirrors src/common/fade_math.h.
vec4 faded_state(uint k, uint model_chain, vec4 s) {
    uint word = uint(instance_wind[HMSM_INSTANCE_WIND_VEC4S * (pc.instance_begin + k)].w);
    if (word == 0u) return s;
    uint keep = uint(chain_rest_rotation[model_chain][0].w);
    if (keep >= (word >> HMSM_FADE_LEVEL_SHIFT)) return s;
    uint clock = uint(wind_table[HMSM_WIND_STEPS + HMSM_WIND_STEP_VEC4S * pc.wind_slot].z);
    uint left = ((word & HMSM_FADE_END_MASK) - clock) & HMSM_FADE_END_MASK;
    if (left == 0u || left >= HMSM_FADE_HORIZON) return vec4(0.0);
    return (float(left) / float(left + 1u)) * s;
}

/// Pass 2's step of either dynamics (PassConstants.dynamics; docs/model.md 3.7, 3.13) for static
/// chain model_chain of group instance k, faded where the instance fades.
vec4 step_angles(uint k, uint model_chain, vec4 s, vec2 g) {
    return faded_state(k, model_chain, pc.dynamics == HMSM_PASS_DYNAMICS_COUPLED ? coupled_step(model_chain, s, g)
                                                                                : integrate_step(model_chain, s, g));
}

/// Pass 2 for model chain c of group instance k under generalized force g: the step (chain_state
/// is updated), then T; T's inputs are read before the state is written.
mat3 chain_integrate(uint k, uint c, uint chain, vec2 g) {
    uint model_chain = pc.model_chain_begin + c;
    vec4 s = step_angles(k, model_chain, chain_state[chain], g);
    mat3 t = local_transform(k, model_chain, chain_parent[model_chain] < 0, s.xy);
    chain_state[chain] = s;
    return t;
}

/// Pass 3, product of T over the chains between c and its 2^round-th ancestor (exclusive) so
/// far: T itself before round 0, else half src_half of chain_rotation.
mat3 product_so_far(uint round, uint src_half, uint chain) {
    return round == 0u ? as_mat3(chain_local[chain])
                       : as_mat3(chain_rotation[half_offset(src_half) + chain]);
}

/// One pass-3 pointer-jumping round for model chain c of group instance k, in device memory;
/// returns the product written.
mat3 compose_jump(uint k, uint c, uint round, uint src_half, uint dst_half) {
    uint chain = state_chain(k, c);
    int ancestor = chain_jump[round * pc.total_model_chains + pc.model_chain_begin + c];
    mat3 r = product_so_far(round, src_half, chain);
    if (ancestor >= 0) r = product_so_far(round, src_half, state_chain(k, uint(ancestor))) * r;
    chain_rotation[half_offset(dst_half) + chain] = as_mat3x4(r);
    return r;
}

/// Pass 5: the offset chain c of group instance k contributes on its own: the instance origin
/// for the trunk, else the attach node's position relative to the parent chain's origin.
vec4 own_offset(uint k, uint c) {
    if (chain_parent[pc.model_chain_begin + c] < 0)
        return vec4(instance_origin[pc.instance_begin + k].xyz, 0.0);
    return node_relative[state_node(k, uint(chain_attach[pc.model_chain_begin + c]))];
}

vec4 sum_so_far(uint k, uint c, uint round, uint src_half) {
    return round == 0u ? own_offset(k, c) : chain_origin[half_offset(src_half) + state_chain(k, c)];
}

/// The joint matrix of state chain `chain`: rows (R row i, O_i).
void store_joint_of(uint chain, mat3 r, vec4 origin) {
    joint_matrix[chain] = mat3x4(vec4(r[0].x, r[1].x, r[2].x, origin.x),
                                 vec4(r[0].y, r[1].y, r[2].y, origin.y),
                                 vec4(r[0].z, r[1].z, r[2].z, origin.z));
}

/// The same with R from half `pose_half` of chain_rotation.
void store_joint(uint chain, uint pose_half, vec4 origin) {
    store_joint_of(chain, as_mat3(chain_rotation[half_offset(pose_half) + chain]), origin);
}

/// One pass-5 pointer-jumping round for model chain c of group instance k, in device memory.
void root_jump(uint k, uint c, uint round, uint src_half, uint dst_half, bool write_joint) {
    int ancestor = chain_jump[round * pc.total_model_chains + pc.model_chain_begin + c];
    vec4 origin = sum_so_far(k, c, round, src_half);
    if (ancestor >= 0) origin += sum_so_far(k, uint(ancestor), round, src_half);
    chain_origin[half_offset(dst_half) + state_chain(k, c)] = origin;
    if (write_joint) store_joint(state_chain(k, c), dst_half, origin);
}

/// The chain `up` depth levels above model chain c, through the 2^round-th ancestors.
uint ancestor_above(uint c, uint up) {
    for (uint round = 0u; up != 0u; ++round, up >>= 1u)
        if ((up & 1u) != 0u) c = uint(chain_jump[round * pc.total_model_chains + pc.model_chain_begin + c]);
    return c;
}

int walk_record[HMSM_WALK_RECORD_INTS];  // the walking chain's record (gpu_layout.h)

/// The ancestor `up` levels above c (walk_record filled for c).
uint walk_ancestor(uint c, uint up) {
    if (up == 0u) return c;
    return up <= HMSM_WALK_PATH_CAPACITY ? uint(walk_record[up]) : ancestor_above(c, up);
}

/// The attach node of the chain `up` levels above c (walk_record filled for c): from the record
/// where the dispatch read it whole, else looked up.
uint walk_attach(uint c, uint up) {
    if (pc.kind == HMSM_DISPATCH_POSE_WALK_FROM_RECORDS && up < HMSM_WALK_ATTACH_CAPACITY)
        return uint(walk_record[HMSM_WALK_ATTACH(up)]);
    return uint(chain_attach[pc.model_chain_begin + walk_ancestor(c, up)]);
}

/// T of model chain x of group instance k from its new angles in chain_state, as integrate
/// computes it (a path-walk step stores no T).
mat3 walk_local(uint k, uint x, bool trunk) {
    return local_transform(k, pc.model_chain_begin + x, trunk, chain_state[state_chain(k, x)].xy);
}

/// Composition::path_walk, passes 3 and 5 for model chain c of group instance k: its ancestors
/// from the trunk down, R = R_parent T and O = O_parent + R_parent l_attach (level by level's
/// operations in its order), each T from the chain's new angles (walk_local), the pose to the
/// joint matrix alone (src/cpu/path_walk.cpp).
void path_walk(uint k, uint c) {
    // The record whole where the dispatch says so (a scene of one active instance), else the
    // ancestors gathered by following chain_parent up (kernels/cuda/chain_math.cuh says why).
    if (pc.kind == HMSM_DISPATCH_POSE_WALK_FROM_RECORDS) {
        uint first = (pc.model_chain_begin + c) * (HMSM_WALK_RECORD_INTS / 4u);
        for (uint q = 0u; q < HMSM_WALK_RECORD_INTS / 4u; ++q) {
            ivec4 w = chain_walk[first + q];
            walk_record[4u * q] = w.x;
            walk_record[4u * q + 1u] = w.y;
            walk_record[4u * q + 2u] = w.z;
            walk_record[4u * q + 3u] = w.w;
        }
    } else {  // the ancestors only; attach nodes are looked up level by level (walk_attach)
        uint up = 0u;
        for (int a = chain_parent[pc.model_chain_begin + c]; a >= 0; a = chain_parent[pc.model_chain_begin + uint(a)]) {
            ++up;
            if (up <= HMSM_WALK_PATH_CAPACITY) walk_record[up] = a;
        }
        walk_record[0] = int(up);
    }
    uint depth = uint(walk_record[0]);
    mat3 r = walk_local(k, walk_ancestor(c, depth), true);
    vec4 origin = vec4(instance_origin[pc.instance_begin + k].xyz, 0.0);
    for (uint level = 1u; level <= depth; ++level) {
        uint x = walk_ancestor(c, depth - level);
        vec3 local = node_local[pc.model_node_begin + walk_attach(c, depth - level)].xyz;
        origin += vec4(r * local, 0.0);
        r = r * walk_local(k, x, false);
    }
    store_joint_of(state_chain(k, c), r, origin);
}

#endif  // HMSM_CHAIN_MATH_GLSL
