// Every fact about a pass in one table (docs/model.md 3.7): the domain its threads run over,
// whether it accumulates down the hierarchy (pointer jumping / level by level), and the buffers
// it reads and writes. Step programs, window plans, access masks, pipeline lists and the
// dispatch switches of every backend derive from this table and from nothing else.
#pragma once

#include "buffers.h"

#include <hmsm/pass.h>
#include <hmsm/config.h>

#include <array>
#include <cstdint>

namespace hmsm::detail {

/// What one thread of a non-hierarchical dispatch covers; hierarchical passes run per chain
/// (or per chain of one level).
enum class PassDomain : uint32_t { chain, node, vertex };

constexpr uint32_t buffer_bit(BufferId id) { return 1u << static_cast<uint32_t>(id); }

// Shorthand for the access columns below: one bit per buffer (bit i = BufferId i).
#define HMSM_B(name) buffer_bit(BufferId::name)

/// X(name, domain, hierarchical, needed_for, walk, reads, writes, walk_reads, walk_writes),
/// in execution order (the same order as HMSM_PASSES in <hmsm/pass.h>; a static_assert below
/// keeps them equal). root_positions writes, with the final O_c, the joint matrix [R_c | O_c]
/// (R_c from compose): the step's pose in 48 bytes, which contour reads (and every reader of a
/// path-walk step; Output::chain_rotations and chain_origins are read from it too).
/// needed_for: the least SimulationConfig::outputs for which a step runs the pass (outputs on
/// demand: joint matrices need passes 1-5 only). A vertex-domain pass takes the vertex layout
/// as its mode; in the packed layout contour's vertex_normal has no elements and is not written.
/// walk: Composition::path_walk runs the pass and this later pass in one dispatch of the pass
/// (none: the pass leads no such dispatch): wind_force with integrate per chain, compose with
/// root_positions by the top-down walk per chain, node_relative with node_world per node.
/// walk_reads, walk_writes: what such a dispatch reads and writes (0 for a pass that leads
/// none). A path-walk step stores no intermediate that only its own dispatch would read: the
/// wind pair keeps g in registers and stores only the new angles S/V; the walk computes each
/// T it multiplies from those angles (so integrate stores no T, and the walk needs no u:
/// its offsets R_parent l_attach come from the static node_local); the node pair keeps u in
/// registers. And the pose is the joint matrix alone: the walk writes no R or O half, the wind
/// and node pairs read R and O from the joint matrix. step_program.cpp pairs the wind passes
/// only where the walk follows.
#define HMSM_PASS_TABLE(X)                                                                        \
    X(wind_force, chain, false, joints, integrate,                                          \
      (HMSM_B(chain_rotation) | HMSM_B(chain_origin) | HMSM_B(chain_constants) |                  \
       HMSM_B(instance_wind) | HMSM_B(wind_table)),                                               \
      (HMSM_B(chain_force)),                                                                      \
      (HMSM_B(joint_matrix) | HMSM_B(chain_constants) | HMSM_B(instance_wind) |                   \
       HMSM_B(wind_table) | HMSM_B(chain_state) | HMSM_B(chain_rest_rotation)),                   \
      (HMSM_B(chain_state)))                                                                      \
    X(integrate, chain, false, joints, none,                                                \
      (HMSM_B(chain_force) | HMSM_B(chain_state) | HMSM_B(chain_constants) |                      \
       HMSM_B(chain_rest_rotation) | HMSM_B(chain_parent) | HMSM_B(instance_yaw) |                \
       HMSM_B(instance_wind) | HMSM_B(wind_table)),                                               \
      (HMSM_B(chain_state) | HMSM_B(chain_local)), 0u, 0u)                                        \
    X(compose, chain, true, joints, root_positions,                                         \
      (HMSM_B(chain_local) | HMSM_B(chain_rotation) | HMSM_B(chain_jump) |                        \
       HMSM_B(chain_parent)),                                                                     \
      (HMSM_B(chain_rotation)),                                                                   \
      (HMSM_B(chain_state) | HMSM_B(chain_walk) | HMSM_B(chain_jump) | HMSM_B(chain_attach) |     \
       HMSM_B(chain_rest_rotation) | HMSM_B(node_local) | HMSM_B(instance_origin) |              \
       HMSM_B(instance_yaw)),                                                                     \
      (HMSM_B(joint_matrix)))                                                                     \
    X(node_relative, node, false, joints, node_world,                                       \
      (HMSM_B(chain_rotation) | HMSM_B(node_owner) | HMSM_B(node_local)),                         \
      (HMSM_B(node_relative)),                                                                    \
      (HMSM_B(joint_matrix) | HMSM_B(node_owner) | HMSM_B(node_local)),                           \
      (HMSM_B(node_world)))                                                                       \
    X(root_positions, chain, true, joints, none,                                            \
      (HMSM_B(node_relative) | HMSM_B(chain_origin) | HMSM_B(chain_jump) |                        \
       HMSM_B(chain_parent) | HMSM_B(chain_attach) | HMSM_B(instance_origin) |                    \
       HMSM_B(chain_rotation)),                                                                   \
      (HMSM_B(chain_origin) | HMSM_B(joint_matrix)), 0u, 0u)                                      \
    X(node_world, node, false, joints_and_nodes, none,                                     \
      (HMSM_B(chain_origin) | HMSM_B(node_relative) | HMSM_B(node_owner)),                        \
      (HMSM_B(node_world)), 0u, 0u)                                                               \
    X(contour, vertex, false, all, none,                                                   \
      (HMSM_B(joint_matrix) | HMSM_B(vertex_chain) |                                              \
       HMSM_B(vertex_rest_position) | HMSM_B(vertex_rest_normal) |                                \
       HMSM_B(vertex_parent_position) | HMSM_B(vertex_parent_normal)),                            \
      (HMSM_B(vertex_position) | HMSM_B(vertex_normal)), 0u, 0u)

/// The two dispatches of the walk that integrates ahead (gpu_layout.h HMSM_DISPATCH_WALK_TOP_POSES
/// and HMSM_DISPATCH_WALK_AHEAD, CUDA forests; step_program.cpp), each a compose walk with more to do: the
/// top poses also read the wind (the next step's profile value) and write the pose halves of
/// the top chains (step_program.h walk_top_depth); the walk ahead reads those and the wind,
/// writes the joint matrix and the next step's angles (to chain_state's twin, which the backend
/// swaps in: counted as a write of chain_state).
inline constexpr uint32_t kWalkTopPosesReads =
    HMSM_B(chain_state) | HMSM_B(chain_jump) | HMSM_B(chain_attach) | HMSM_B(chain_parent) |
    HMSM_B(chain_rest_rotation) | HMSM_B(node_local) | HMSM_B(instance_origin) | HMSM_B(instance_yaw) |
    HMSM_B(instance_wind) | HMSM_B(wind_table);
inline constexpr uint32_t kWalkTopPosesWrites = HMSM_B(chain_rotation) | HMSM_B(chain_origin);
inline constexpr uint32_t kWalkAheadReads =
    kWalkTopPosesReads | HMSM_B(chain_rotation) | HMSM_B(chain_origin) | HMSM_B(chain_constants);
inline constexpr uint32_t kWalkAheadWrites = HMSM_B(joint_matrix) | HMSM_B(chain_state);

/// The coupled dynamics (docs/model.md 3.13; PassConstants.dynamics) adds to the columns above
/// (to a path walk's wind pair both): wind_force gathers its children's loads of the last step
/// (one half of chain_load, anywhere in the instance) through the rest rotations their records
/// hold, reads its own rates for the aerodynamic damping and stores its load in the other half;
/// integrate reads the chain's record.
inline constexpr uint32_t kCoupledWindForceReads =
    HMSM_B(chain_state) | HMSM_B(chain_load) | HMSM_B(chain_dynamics);
inline constexpr uint32_t kCoupledWindForceWrites = HMSM_B(chain_load);
inline constexpr uint32_t kCoupledIntegrateReads = HMSM_B(chain_dynamics);
/// The articulated exchange (docs/model.md 3.13): wind_force reads the chain's record and rates
/// and stores its impulse where integrate writes T (chain_local), alone or as a path walk's wind
/// pair, which then runs pass 1 only (integrate follows as a dispatch of its own); integrate, an
/// INSTANCE_SWEEP, reads every record, impulse and state of its instances and keeps its sweeps'
/// scratch in chain_local, chain_load and chain_force (gpu_layout.h).
inline constexpr uint32_t kArticulatedWindForceReads = HMSM_B(chain_state) | HMSM_B(chain_dynamics);
inline constexpr uint32_t kArticulatedWindForceWrites = HMSM_B(chain_local);
inline constexpr uint32_t kArticulatedIntegrateReads =
    HMSM_B(chain_dynamics) | HMSM_B(chain_local) | HMSM_B(chain_load) | HMSM_B(chain_force);
inline constexpr uint32_t kArticulatedIntegrateWrites = HMSM_B(chain_load) | HMSM_B(chain_force);

/// What one dispatch runs (PassConstants.kind): X(name, NAME, passes) with NAME the suffix of its
/// HMSM_DISPATCH_* number in gpu_layout.h (shared with CUDA and GLSL) and `passes` the passes
/// whose dispatches may be of this kind (bit i = Pass i). Every backend switches on the kind.
#define HMSM_DISPATCH_KINDS(X)                                                                          \
    X(per_element, PER_ELEMENT,                                                                         \
      HMSM_P(wind_force) | HMSM_P(integrate) | HMSM_P(node_relative) | HMSM_P(node_world))             \
    X(jump_round, JUMP_ROUND, HMSM_P(compose) | HMSM_P(root_positions))                                 \
    X(jump_rounds_in_dispatch, JUMP_ROUNDS_IN_DISPATCH, HMSM_P(compose) | HMSM_P(root_positions))       \
    X(level, LEVEL, HMSM_P(compose) | HMSM_P(root_positions))                                           \
    X(wind_pair, WIND_PAIR, HMSM_P(wind_force))                                                         \
    X(pose_walk, POSE_WALK, HMSM_P(compose))                                                            \
    X(pose_walk_from_records, POSE_WALK_FROM_RECORDS, HMSM_P(compose))                                  \
    X(node_pair, NODE_PAIR, HMSM_P(node_relative))                                                      \
    X(walk_top_poses, WALK_TOP_POSES, HMSM_P(compose))                                                  \
    X(walk_ahead, WALK_AHEAD, HMSM_P(compose))                                                          \
    X(contour_separate, CONTOUR_SEPARATE, HMSM_P(contour))                                              \
    X(contour_packed, CONTOUR_PACKED, HMSM_P(contour))                                                  \
    X(instance_sweep, INSTANCE_SWEEP, HMSM_P(integrate))

#define HMSM_P(name) (1u << uint32_t(Pass::name))
enum class DispatchKind : uint32_t {
#define HMSM_DISPATCH_KIND_ENUM(name, NAME, passes) name = HMSM_DISPATCH_##NAME,
    HMSM_DISPATCH_KINDS(HMSM_DISPATCH_KIND_ENUM)
#undef HMSM_DISPATCH_KIND_ENUM
};

struct DispatchKindInfo {
    DispatchKind kind;
    uint32_t passes;  ///< the passes whose dispatches may be of this kind (bit i = Pass i)
};
inline constexpr DispatchKindInfo kDispatchKinds[] = {
#define HMSM_DISPATCH_KIND_INFO(name, NAME, passes) {DispatchKind::name, passes},
    HMSM_DISPATCH_KINDS(HMSM_DISPATCH_KIND_INFO)
#undef HMSM_DISPATCH_KIND_INFO
};
#undef HMSM_P

/// The kinds are numbered 0, 1, ... in the order listed, as gpu_layout.h numbers them.
constexpr bool dispatch_kinds_are_numbered_in_order() {
    uint32_t i = 0;
    for (const DispatchKindInfo& k : kDispatchKinds)
        if (uint32_t(k.kind) != i++) return false;
    return i == HMSM_DISPATCH_KIND_COUNT;
}
static_assert(dispatch_kinds_are_numbered_in_order(), "HMSM_DISPATCH_KINDS must list HMSM_DISPATCH_* 0, 1, ...");
/// Whether a dispatch of `pass` may be of `kind` (an unknown kind fits no pass).
constexpr bool kind_fits_pass(uint32_t kind, Pass pass) {
    return kind < HMSM_DISPATCH_KIND_COUNT && (kDispatchKinds[kind].passes >> uint32_t(pass) & 1u);
}
/// The kinds of Composition::path_walk that run a pass and its walk partner in one dispatch
/// (the walk ahead's two included: compose walks with more to do).
constexpr bool runs_walk_pair(DispatchKind kind) {
    switch (kind) {
        case DispatchKind::wind_pair:
        case DispatchKind::pose_walk:
        case DispatchKind::pose_walk_from_records:
        case DispatchKind::node_pair:
        case DispatchKind::walk_top_poses:
        case DispatchKind::walk_ahead: return true;
        default: return false;
    }
}

/// The pass column `walk` names: the pass a path-walk dispatch also runs, or none.
enum class WalkPartner : int32_t {
    none = -1,
    integrate = int32_t(Pass::integrate),
    root_positions = int32_t(Pass::root_positions),
    node_world = int32_t(Pass::node_world),
};

struct PassInfo {
    Pass pass;
    PassDomain domain;
    bool hierarchical;
    Outputs needed_for;
    WalkPartner walk;
    uint32_t reads;
    uint32_t writes;
    uint32_t walk_reads;
    uint32_t walk_writes;
};

inline constexpr std::array<PassInfo, kPassCount> kPassTable = {{
#define HMSM_PASS_INFO(name, domain, hierarchical, needed_for, walk, reads, writes, walk_reads, walk_writes) \
    {Pass::name, PassDomain::domain, hierarchical, Outputs::needed_for, WalkPartner::walk, reads, writes,        \
     walk_reads, walk_writes},
    HMSM_PASS_TABLE(HMSM_PASS_INFO)
#undef HMSM_PASS_INFO
}};
#undef HMSM_B

constexpr bool pass_table_in_order() {
    for (uint32_t i = 0; i < kPassCount; ++i)
        if (kPassTable[i].pass != kAllPasses[i]) return false;
    return true;
}
static_assert(pass_table_in_order(), "HMSM_PASS_TABLE must list HMSM_PASSES in order");

constexpr const PassInfo& pass_info(Pass pass) { return kPassTable[static_cast<uint32_t>(pass)]; }
constexpr bool is_hierarchical(Pass pass) { return pass_info(pass).hierarchical; }
constexpr PassDomain pass_domain(Pass pass) { return pass_info(pass).domain; }
/// Whether a step that produces `outputs` runs `pass` (Outputs are ordered joints <
/// joints_and_nodes < all).
constexpr bool pass_runs_for(Pass pass, Outputs outputs) {
    return uint32_t(pass_info(pass).needed_for) <= uint32_t(outputs);
}

/// The buffers the passes `passes` (bit i = Pass i) read, resp. write, together: the access of a
/// dispatch that runs several passes (a path-walk pair).
constexpr uint32_t reads_of_passes(uint32_t passes) {
    uint32_t bits = 0;
    for (const PassInfo& p : kPassTable)
        if (passes >> uint32_t(p.pass) & 1u) bits |= p.reads;
    return bits;
}
constexpr uint32_t writes_of_passes(uint32_t passes) {
    uint32_t bits = 0;
    for (const PassInfo& p : kPassTable)
        if (passes >> uint32_t(p.pass) & 1u) bits |= p.writes;
    return bits;
}
/// Composition::path_walk: the passes a path-walk dispatch of `pass` runs (bit i = Pass i): the
/// pass and its walk partner; 0 where the pass leads no such dispatch.
constexpr uint32_t walk_passes(Pass pass) {
    const WalkPartner partner = pass_info(pass).walk;
    return partner == WalkPartner::none ? 0u : (1u << uint32_t(pass)) | (1u << uint32_t(partner));
}
/// Every pass is a walk partner of at most one earlier pass and leads at most one walk.
constexpr bool walk_partners_are_later_and_unique() {
    uint32_t partners = 0;
    for (const PassInfo& p : kPassTable) {
        if (p.walk == WalkPartner::none) continue;
        const uint32_t bit = 1u << uint32_t(p.walk);
        const bool later = uint32_t(p.walk) > uint32_t(p.pass);
        if (!later || (partners & bit) || walk_passes(Pass(p.walk)) != 0) return false;
        partners |= bit;
    }
    return true;
}
static_assert(walk_partners_are_later_and_unique(), "a walk partner must be a later pass that leads no walk");
/// A walk dispatch has accesses exactly where the pass leads one, and writes only what its two
/// passes write (it leaves intermediates out, never adds outputs).
constexpr bool walk_accesses_are_consistent() {
    for (const PassInfo& p : kPassTable) {
        const bool leads = p.walk != WalkPartner::none;
        if (leads != (p.walk_reads != 0) || leads != (p.walk_writes != 0)) return false;
        if ((p.walk_writes & ~writes_of_passes(walk_passes(p.pass))) != 0) return false;
    }
    return true;
}
static_assert(walk_accesses_are_consistent(),
              "walk_reads/walk_writes: set exactly for walk leaders, writes within the pair's");

}  // namespace hmsm::detail
