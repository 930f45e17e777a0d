// Host buffers of the CPU backend (float: the paper's serial baseline; double: the oracle) and
// the element mapping every pass uses. Same logical layout as gpu_layout.h; matrices are glm
// 3x3 here.
#pragma once

#include "../backend.h"
#include "../common/element_index.h"  // Element, element_of, state_chain, state_node

#include <glm/mat3x3.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <array>
#include <vector>

namespace hmsm::detail::cpu {

template <class T>
struct State {
    using vec2 = glm::vec<2, T>;
    using vec3 = glm::vec<3, T>;
    using vec4 = glm::vec<4, T>;
    using mat3 = glm::mat<3, 3, T>;
    /// A joint matrix as stored: three vec4 rows (R row i, O_i), gpu_layout.h.
    using joint = glm::mat<3, 4, T>;

    // Model and instance scope (uploaded once).
    std::vector<int32_t> chain_parent, chain_jump, chain_attach, node_owner, chain_walk;
    std::vector<glm::ivec2> vertex_chain;
    std::vector<mat3> chain_rest_rotation;
    /// Per static chain: its keep rank, the rank of the coarsest level of its scene model that
    /// keeps it (gpu_layout.h HMSM_FADE_*; on the devices column 0's w of chain_rest_rotation).
    std::vector<uint32_t> chain_keep_level;
    std::vector<vec4> chain_constants, node_local;
    /// The coupled dynamics' records (gpu_layout.h HMSM_CHAIN_DYNAMICS_VEC4S; empty under paper).
    std::vector<std::array<T, 4 * HMSM_CHAIN_DYNAMICS_VEC4S>> chain_dynamics;
    /// The articulated exchange's records (HMSM_CHAIN_ARTICULATED_VEC4S; empty otherwise; on the
    /// devices in chain_dynamics' place).
    std::vector<std::array<T, 4 * HMSM_CHAIN_ARTICULATED_VEC4S>> chain_articulated;
    std::vector<vec4> vertex_rest_position, vertex_rest_normal;
    std::vector<vec4> vertex_parent_position, vertex_parent_normal;
    std::vector<vec4> instance_origin, instance_yaw;
    // Live control: the wind per instance and the wind table (gpu_layout.h).
    std::vector<std::array<T, 4 * HMSM_INSTANCE_WIND_VEC4S>> instance_wind;
    std::vector<vec4> wind_table;
    /// The listed dispatches' table (gpu_layout.h HMSM_BINDING_INSTANCE_TABLE): allocated as on
    /// the devices, read by no CPU pass (the CPU backends run no listed dispatch).
    std::vector<glm::ivec4> instance_table;
    // Per-instance state.
    std::vector<vec4> chain_state;
    std::vector<vec2> chain_force;
    std::vector<vec2> chain_load;      // coupled: (g_x, g_z), the load of the last step
    /// T; under the articulated exchange pass 1's impulse for pass 2's sweeps within a step
    /// (scalar i in column i / 3, row i % 3; the CPU sweeps keep their scratch to themselves).
    std::vector<mat3> chain_local;
    std::vector<mat3> chain_rotation;  // two halves of total_chains (the allocated chains)
    std::vector<vec4> node_relative;
    std::vector<vec4> chain_origin;    // two halves
    std::vector<vec4> node_world;
    std::vector<vec4> vertex_position, vertex_normal;
    std::vector<joint> joint_matrix;   // [R_c | O_c] by rows
    // Uniforms.
    T dt{}, max_angle{}, fix_weight{};
    uint64_t total_chains = 0;
};

/// Whether group instance k is paused (inactive, frozen): a dispatch may cover paused instances
/// between active ones (it says so in params.w) and skips their elements (gpu_layout.h,
/// instance_wind element 0's z).
template <class T>
bool instance_paused(const State<T>& s, const gpu::PassConstants& pc, uint32_t k) {
    return pc.params.w != 0.0f && s.instance_wind[pc.instance_begin + k][2] != T(0);
}

/// Stores the joint matrix [R | O] of state chain `chain` as three rows (R row i, O_i).
template <class T>
void store_joint(State<T>& s, uint64_t chain, const typename State<T>::mat3& r,
                 const typename State<T>::vec4& o) {
    auto& m = s.joint_matrix[chain];
    for (int i = 0; i < 3; ++i) m[i] = typename State<T>::vec4(r[0][i], r[1][i], r[2][i], o[i]);
}

/// The pose a joint matrix holds: R (rebuilt by columns) and O, the floats stored.
template <class T>
typename State<T>::mat3 joint_rotation(const State<T>& s, uint64_t chain) {
    const auto& m = s.joint_matrix[chain];
    return typename State<T>::mat3(m[0][0], m[1][0], m[2][0], m[0][1], m[1][1], m[2][1], m[0][2], m[1][2], m[2][2]);
}
template <class T>
typename State<T>::vec3 joint_origin(const State<T>& s, uint64_t chain) {
    const auto& m = s.joint_matrix[chain];
    return typename State<T>::vec3(m[0][3], m[1][3], m[2][3]);
}

/// The work items [begin, end) of one dispatch that one call of a pass runs, in order. An item
/// is a thread of the dispatch (element i, gpu_layout.h), except in a
/// HMSM_DISPATCH_JUMP_ROUNDS_IN_DISPATCH dispatch, where it is a group instance running every round
/// (a workgroup on a GPU). Distinct items of one dispatch write distinct elements and read
/// only what earlier dispatches (or, in-dispatch, earlier rounds of the same instance) wrote,
/// so disjoint ranges may run concurrently (the cpu-parallel backend) with the same float
/// results as one serial call over all items.
struct Range {
    uint32_t begin = 0, end = 0;
};
/// Whether a work item of a dispatch of `pass` is a group instance (see Range): every round of
/// pointer jumping in one dispatch, or the articulated exchange's sweeps.
inline bool items_are_instances(Pass pass, const gpu::PassConstants& pc) {
    return (is_hierarchical(pass) && pc.kind == HMSM_DISPATCH_JUMP_ROUNDS_IN_DISPATCH) ||
           pc.kind == HMSM_DISPATCH_INSTANCE_SWEEP;
}
/// Number of work items of a dispatch of `pass` (see Range).
inline uint32_t work_items(Pass pass, const gpu::PassConstants& pc) {
    return items_are_instances(pass, pc) ? pc.element_count / pc.model_chain_count : pc.element_count;
}
/// Model elements (chains, nodes or vertices) one work item of `pass` touches, for chunking: an
/// instance item runs every round over its chains (or both sweeps).
inline uint32_t elements_per_item(Pass pass, const gpu::PassConstants& pc) {
    if (!items_are_instances(pass, pc)) return 1;
    return pc.model_chain_count * (pc.kind == HMSM_DISPATCH_INSTANCE_SWEEP ? 2u : pc.round);
}

/// The three kinds of dispatch of a hierarchical pass (compose, root_positions) running the work
/// items `r`. LEVEL: level(dst, instance, chain, parent) for each chain of one level, in place in
/// half dst (an element offset). JUMP_ROUNDS_IN_DISPATCH: the work items are instances, and
/// round(round, src_half, dst_half, chains, last) runs over all their chains, round after round.
/// JUMP_ROUND: round(...) over `r` itself (last is true). No other kind runs these passes apart
/// (pass_table.h HMSM_DISPATCH_KINDS).
template <class T, class Level, class Round>
void run_hierarchical(const State<T>& s, const gpu::PassConstants& pc, Range r, Level level, Round round) {
    switch (pc.kind) {
        case HMSM_DISPATCH_LEVEL: {
            const uint64_t dst = uint64_t(pc.dst_half) * s.total_chains;
            for (uint32_t i = r.begin; i < r.end; ++i) {
                const Element e = element_of(i, pc.level_count);
                if (instance_paused(s, pc, e.instance)) continue;
                const int32_t c = int32_t(pc.level_begin + e.index);
                level(dst, e.instance, c, s.chain_parent[pc.model_chain_begin + c]);
            }
            return;
        }
        case HMSM_DISPATCH_JUMP_ROUNDS_IN_DISPATCH: {
            const Range chains{r.begin * pc.model_chain_count, r.end * pc.model_chain_count};
            for (uint32_t k = 0; k < pc.round; ++k)
                round(k, HMSM_HALF_READ(k), HMSM_HALF_WRITTEN(k), chains, k + 1 == pc.round);
            return;
        }
        case HMSM_DISPATCH_JUMP_ROUND: return round(pc.round, pc.src_half, pc.dst_half, r, true);
        default: return;
    }
}

// The seven passes; each runs the work items `r` of one dispatch serially.
template <class T> void wind_force(State<T>& s, const gpu::PassConstants& pc, uint32_t wind_slot, Range r);
template <class T> void integrate(State<T>& s, const gpu::PassConstants& pc, uint32_t wind_slot, Range r);
template <class T> void compose(State<T>& s, const gpu::PassConstants& pc, Range r);
template <class T> void node_relative(State<T>& s, const gpu::PassConstants& pc, Range r);
template <class T> void root_positions(State<T>& s, const gpu::PassConstants& pc, Range r);
template <class T> void node_world(State<T>& s, const gpu::PassConstants& pc, Range r);
template <class T> void contour(State<T>& s, const gpu::PassConstants& pc, Range r);
/// Composition::path_walk: passes 3 and 5 for the chains `r` by the top-down walk (path_walk.cpp).
template <class T> void path_walk(State<T>& s, const gpu::PassConstants& pc, Range r);
/// Composition::path_walk's wind pair: passes 1 and 2 per chain, storing only the angles.
template <class T> void wind_force_and_integrate(State<T>& s, const gpu::PassConstants& pc, uint32_t wind_slot, Range r);
/// Composition::path_walk's node pair: passes 4 and 6 per node, storing only node_world.
template <class T> void node_relative_and_world(State<T>& s, const gpu::PassConstants& pc, Range r);
/// The coupled dynamics (coupled_dynamics.cpp, docs/model.md 3.13): pass 1's g of state chain c
/// (static chain model_chain, group instance `instance`) under the wind w_local in its frame,
/// its children's loads read from half `load_half` of chain_load (the half the last step wrote;
/// the caller stores g in the other); and pass 2's exact step of its angles under g (stores S/V,
/// returns S).
template <class T>
typename State<T>::vec2 coupled_force(const State<T>& s, const gpu::PassConstants& pc, uint32_t instance,
                                      uint64_t c, uint32_t model_chain, const typename State<T>::vec3& w_local,
                                      uint32_t load_half);
template <class T>
typename State<T>::vec2 coupled_integrate_angles(State<T>& s, uint32_t model_chain, uint64_t c,
                                                 const typename State<T>::vec2& g);
/// The articulated exchange (articulated_dynamics.cpp, docs/model.md 3.13): pass 1 stores state
/// chain c's impulse under the wind w_local in its frame; pass 2 sweeps the instances of `r`
/// (work items are group instances), steps their joints, relaxes fading chains and stores T.
template <class T>
void articulated_impulse(State<T>& s, uint64_t c, uint32_t model_chain, const typename State<T>::vec3& w_local);
template <class T>
void articulated_integrate(State<T>& s, const gpu::PassConstants& pc, uint32_t wind_slot, Range r);
/// Relaxes state chain c (static chain model_chain, group instance `instance`) by the fade of
/// the step of wind-table slot wind_slot where one relaxes it; returns S.
template <class T>
typename State<T>::vec2 relax_fading(State<T>& s, const gpu::PassConstants& pc, uint32_t wind_slot, uint32_t instance,
                                     uint32_t model_chain, uint64_t c);
/// Pass 2's halves: the symplectic Euler step of state chain c of static chain model_chain under
/// g (stores S/V, returns S), and the local transform T of static chain model_chain of global
/// instance `instance` at angles S.
template <class T>
typename State<T>::vec2 integrate_angles(State<T>& s, uint32_t model_chain, uint64_t c, const typename State<T>::vec2& g);
/// Pass 2's step of state chain c (static chain model_chain, group instance `instance`) under g
/// by either dynamics, then the fade of the step of wind-table slot wind_slot where one relaxes
/// the chain (stores S/V, returns S).
template <class T>
typename State<T>::vec2 step_angles(State<T>& s, const gpu::PassConstants& pc, uint32_t wind_slot, uint32_t instance,
                                    uint32_t model_chain, uint64_t c, const typename State<T>::vec2& g);
template <class T>
typename State<T>::mat3 local_transform(const State<T>& s, uint32_t model_chain, uint32_t instance,
                                        const typename State<T>::vec2& angle);

}  // namespace hmsm::detail::cpu
