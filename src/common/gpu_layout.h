// The one description of hmsm's device buffers and per-dispatch constants, included by C++,
// CUDA and GLSL (shaders compile with -I src). Only the preprocessor and plain structs here.
//
// Storage is structure-of-arrays of 16-byte elements (vec4, never vec3). A 3x3 matrix is three
// vec4 columns (48 bytes). "Model" buffers hold static data once per model (shared by all its
// instances); "state" buffers hold one element per chain/node/vertex of every instance,
// instance-major. The ping-pong buffers chain_rotation and chain_origin have two halves of
// total_chains elements each (the paper's M_temp and Root Positions temporaries).
#ifndef HMSM_GPU_LAYOUT_H
#define HMSM_GPU_LAYOUT_H

/// Threads per workgroup / CUDA block, for every pass.
#define HMSM_WORKGROUP_SIZE 64
/// Pointer-jumping rounds supported (chain depth up to 2^8 - 1).
#define HMSM_MAX_JUMP_ROUNDS 8

// Binding numbers (Vulkan descriptor set 0) = hmsm::detail::BufferId values.
// Model-scope static data:
#define HMSM_BINDING_CHAIN_PARENT 0          // int   per model chain: parent chain, -1 trunk
#define HMSM_BINDING_CHAIN_JUMP 1            // int   per (round, model chain): 2^round-th ancestor or -1; round-major, stride total_model_chains
#define HMSM_BINDING_CHAIN_ATTACH 2          // int   per model chain: attach node (model-local)
#define HMSM_BINDING_CHAIN_REST_ROTATION 3   // mat3x4 per model chain: Q_c; column 0's w: its keep rank (below)
#define HMSM_BINDING_CHAIN_CONSTANTS 4       // vec4  per model chain: (I, K, D, A)
#define HMSM_BINDING_NODE_OWNER 5            // int   per model node: owning chain (model-local)
#define HMSM_BINDING_NODE_LOCAL 6            // vec4  per model node: l_n (xyz)
#define HMSM_BINDING_VERTEX_CHAIN 7          // ivec2 per model vertex: (chain, fix-up parent chain or -1)
#define HMSM_BINDING_VERTEX_REST_POSITION 8  // vec4  per model vertex: in its chain's frame
#define HMSM_BINDING_VERTEX_REST_NORMAL 9    // vec4
#define HMSM_BINDING_VERTEX_PARENT_POSITION 10  // vec4: fix-up vertex in the parent chain's frame
#define HMSM_BINDING_VERTEX_PARENT_NORMAL 11    // vec4
// Instance scope:
#define HMSM_BINDING_INSTANCE_ORIGIN 12      // vec4 per instance: (origin xyz, 0)
#define HMSM_BINDING_INSTANCE_YAW 13         // vec4 per instance: (cos yaw, sin yaw, 0, 0)
// State, one element per chain/node/vertex of every instance:
#define HMSM_BINDING_CHAIN_STATE 14          // vec4 per chain: (theta_x, theta_z, v_x, v_z)
#define HMSM_BINDING_CHAIN_FORCE 15          // vec2 per chain: generalized force g
#define HMSM_BINDING_CHAIN_LOCAL 16          // mat3x4 per chain: local transform T
#define HMSM_BINDING_CHAIN_ROTATION 17       // mat3x4 per chain, 2 halves: total rotation R
#define HMSM_BINDING_NODE_RELATIVE 18        // vec4 per node: u_n
#define HMSM_BINDING_CHAIN_ORIGIN 19         // vec4 per chain, 2 halves: chain origin O
#define HMSM_BINDING_NODE_WORLD 20           // vec4 per node: W_n
#define HMSM_BINDING_VERTEX_POSITION 21      // vec4 per vertex: (x, y, z, 1), packed: (x, y, z, normal word)
#define HMSM_BINDING_VERTEX_NORMAL 22        // vec4 per vertex: (nx, ny, nz, 0); packed: no elements
// Live control (docs/model.md 3.5, 3.9), written by the host between steps:
#define HMSM_BINDING_INSTANCE_WIND 23        // 9 vec4 per instance: HMSM_INSTANCE_WIND_* below
#define HMSM_BINDING_WIND_TABLE 24           // HMSM_WIND_TABLE_ELEMENTS vec4: HMSM_WIND_* below
// Joint matrix M_c = [R_c | O_c] per chain (docs/formats.md "Joint matrices"): three vec4 ROWS
// (R_c row i, O_c.i), 48 bytes, written by root_positions where it writes the final O_c.
#define HMSM_BINDING_JOINT_MATRIX 25         // mat3x4 per chain: rows (R row 0, O.x), (R row 1, O.y), (R row 2, O.z)
// Model scope, for Composition::path_walk:
#define HMSM_BINDING_CHAIN_WALK 26           // HMSM_WALK_RECORD_INTS int per model chain: its walk record (below)
// The coupled dynamics (docs/model.md 3.13; no elements under the paper's), by its exchange:
#define HMSM_BINDING_CHAIN_DYNAMICS 27       // held: HMSM_CHAIN_DYNAMICS_VEC4S vec4 per model chain; articulated: HMSM_CHAIN_ARTICULATED_VEC4S (below)
#define HMSM_BINDING_CHAIN_LOAD 28           // vec2 per chain, 2 halves: (g_x, g_z), the load g of a step (articulated: scratch, below)
// Listed dispatches (PassConstants.instance_list below), written by the host with the program:
#define HMSM_BINDING_INSTANCE_TABLE 29       // uvec4 per list entry: (chain_begin, node_begin, vertex_begin, instance)
#define HMSM_BINDING_COUNT 30

/// What PassConstants.dynamics says the passes integrate (hmsm::Dynamics values).
#define HMSM_PASS_DYNAMICS_PAPER 0u
#define HMSM_PASS_DYNAMICS_COUPLED 1u
/// The coupled dynamics with the articulated exchange (ModelOptions::exchange): pass 1 stores
/// each chain's own wind impulse, pass 2 solves the whole instance's joints in two sweeps
/// (src/common/articulated_math.h; an INSTANCE_SWEEP dispatch below).
#define HMSM_PASS_DYNAMICS_ARTICULATED 2u
/// A chain's record under the articulated exchange (binding HMSM_BINDING_CHAIN_DYNAMICS, in the
/// held exchange's place): HMSM_CHAIN_ARTICULATED_VEC4S vec4, on the devices stored by vec4 as
/// the held records below, as scalars (docs/model.md 3.13; spatial vectors in the chain's rest
/// frame about its joint, angular first; I^A its articulated inertia, S = [e_x e_z] of the
/// angular part):
///   0-5: U_x = I^A S_x        6-11: U_z = I^A S_z
///   12-15: (G_xx, G_xz, G_zz, eta): G = (S^T I^A S + the armature)^-1; eta as in coupled
///   16 + 4 j (j = 0, 1, 2): (column j of Q_c, d_j): the rest rotation in the parent's frame
///          and the joint's position d in the parent's frame
///   28-31: (dt q_ref M_own, dt q_ref A_own): the own wind's impulse moment and force
///   32-35: (dt K_x, dt K_z, dt D_x + theta_x dt^2 K_x, dt D_z + theta_z dt^2 K_z)
///   36-39: (theta_x dt, theta_z dt, I_x, I_z): I the joint's articulated inertia S^T I^A S
///   40-43: (aero_x dt / I_x, aero_z dt / I_z, first child, child count)
///   44-47: (first chain of its depth, end of its depth, 0, 0): the chains are breadth first,
///          so a depth is a range, which the sweeps take one after the other
/// Model-local chain ids are floats (< 2^24). Within a step a chain's T (chain_local), which
/// integrate writes last, holds its scratch: pass 1 stores there its impulse (column 0: the
/// wind's moment and force x; column 1: force y and z, the aerodynamic damping's impulse about x
/// and z); the up sweep replaces it by the force the chain passes to its parent (column 0,
/// column 1 xy) and its w (column 1 zw). On the way down its spatial change of motion goes to
/// its halves of chain_load (angular x y, angular z and linear x) and chain_force (linear y z),
/// which its children read before it writes T.
#define HMSM_CHAIN_ARTICULATED_VEC4S 12u
/// A chain's record of the coupled dynamics (binding HMSM_BINDING_CHAIN_DYNAMICS), vec4 j of
/// HMSM_CHAIN_DYNAMICS_VEC4S; axis x is theta_x, axis z theta_z (docs/model.md 3.13). On the
/// devices the records are stored by vec4 (structure of arrays): vec4 j of model chain c is
/// vec4 j * total_model_chains + c, so that a warp's loads of one vec4 of consecutive chains
/// are contiguous (the host's SceneData::chain_dynamics holds them record by record).
///   j = 0: transition about x over dt, (a11, a12, a21, a22): with y = S - g / K,
///          (y, V) <- (a11 y + a12 V, a21 y + a22 V)
///   j = 1: transition about z
///   j = 2: (I_x / dt, I_z / dt, 1 / K_x, 1 / K_z)
///   j = 3: (aero_x dt / I_x, aero_z dt / I_z, first child, child count): the aerodynamic damping
///          per sqrt(|w|) over one step; the children as floats (model-local chain ids, < 2^24)
///   j = 4: (q_ref M_c, eta): the wind moment, torque = (q_ref M_c) x w_local, and the motion
///          drag per unit rate over the aerodynamic damping per sqrt(|w|): the damping is
///          aero (sqrt(|w|) + eta |V|)
///   j = 5: (Q_00, Q_02, Q_20, Q_22): rows x and z of columns x and z of the rest rotation Q_c,
///          which pass the chain's load (x, z) on into its parent's frame; the parent reads it
///          beside the load, so a gather over the children reads one vec4 of each record
/// Per-step constants are folded here on the host so that the passes divide nowhere.
#define HMSM_CHAIN_DYNAMICS_VEC4S 6u
#define HMSM_CHAIN_DYNAMICS_PASSING 5u

/// The wind of docs/model.md 3.5 on the device. Float backends never see the clock tau or a
/// phase beyond a few units: the host reduces tau mod 2 and the turbulent and atmospheric mode
/// phases mod 1 in double and hands over only those.
///
/// instance_wind, 9 vec4 per instance i (element 9 i + j):
///   j = 0: (lambda_i, phi_i mod 2, paused, fade)  wind scale; wind phase phi_i = p_i - f (o_i.d)/v;
///          paused 1 while the instance is inactive, else 0: a dispatch may cover paused
///          instances between active ones (live_control.cpp); where it does (params.w = 1), it
///          skips their elements; fade: the instance's fade word (HMSM_FADE_* below), 0 when it
///          does not fade
///   j = 1..8: frac(m_k phi_i) for the turbulent modes k = 4 (j - 1) .. 4 (j - 1) + 3;
///          atmospheric: the spatial phases frac(kx_k (p_i - o_i.e_x) - ky_k o_i.e_y - kz_k o_i.e_z)
/// wind_table, vec4 elements:
///   [HMSM_WIND_AMPLITUDES, +8): turbulent or atmospheric amplitudes a_k (k = 4 e + component);
///       atmospheric: modes [0, 16) u', [16, 24) v', [24, 32) w'
///   HMSM_WIND_VECTOR: (s d, number of force fields): strength times unit direction
///   HMSM_WIND_LATERAL, HMSM_WIND_VERTICAL: (s e_y, 0), (s e_z, 0), the atmospheric profile's
///       cross-wind directions times strength (hmsm::wind_frame)
///   [HMSM_WIND_FIELDS, +2 per field): (centre xyz, radius), (F xyz, kind) with kind 0 =
///       directional (force h F), 1 = radial (force h F.x unit(x - centre))
///   [HMSM_WIND_STEPS + 9 s, +9): step slot s: (tau mod 2, h, n mod HMSM_FADE_PERIOD, 0) with
///       h = n mod 2 for step n (the half of chain_load the step writes; it reads the other; n
///       mod HMSM_FADE_PERIOD is the fades' clock), then frac(m_k tau + u_k)
///       (atmospheric: frac(kx_k tau + u_k), tau in metres) as instance_wind's elements 1..8.
///       A wind_force dispatch reads slot pc.wind_slot.
/// Fades to a coarser level (docs/model.md 3.12), run in pass 2. A scene model's levels ranked by chain
/// count, finest first, are nested. Fade word: L * HMSM_FADE_PERIOD + (e mod HMSM_FADE_PERIOD), L the
/// rank of the level faded to, e the number of the fade's last step (below 2^24: exact in a float).
/// A model chain's keep rank (chain_rest_rotation, column 0's w) is the rank of the coarsest level
/// keeping it; the fade scales a chain whose keep rank is below L. At step n, with m = (e - n) mod
/// HMSM_FADE_PERIOD the steps left after it: sigma = m / (m + 1) while 0 < m < HMSM_FADE_HORIZON,
/// else 0 (the fade is over: the folded chains stay at rest).
#define HMSM_FADE_PERIOD 131072u
#define HMSM_FADE_END_MASK 131071u
#define HMSM_FADE_LEVEL_SHIFT 17u
#define HMSM_FADE_HORIZON 65536u
/// Levels of detail a model may have (level 0 included): the fade word's L stays below 2^7.
#define HMSM_MAX_LOD_LEVELS 128u
#define HMSM_WIND_MODES 32
#define HMSM_WIND_MODE_VEC4S 8
#define HMSM_WIND_MODES_U_VEC4S 4  // atmospheric: mode vec4s [0, 4) u', [4, 6) v', [6, 8) w'
#define HMSM_WIND_MODES_V_VEC4S 2
#define HMSM_INSTANCE_WIND_VEC4S 9
#define HMSM_MAX_FORCE_FIELDS 16
#define HMSM_WIND_AMPLITUDES 0
#define HMSM_WIND_VECTOR 8
#define HMSM_WIND_LATERAL 9
#define HMSM_WIND_VERTICAL 10
#define HMSM_WIND_FIELDS 11
#define HMSM_WIND_STEPS (HMSM_WIND_FIELDS + 2 * HMSM_MAX_FORCE_FIELDS)
#define HMSM_WIND_STEP_VEC4S 9
/// Steps one Backend::run may take (one slot each); Simulation::step runs longer calls in chunks.
#define HMSM_WIND_STEP_SLOTS 256
#define HMSM_WIND_TABLE_ELEMENTS (HMSM_WIND_STEPS + HMSM_WIND_STEP_VEC4S * HMSM_WIND_STEP_SLOTS)
/// wind profiles (PassConstants.profile; hmsm::WindProfile values, checked in options.cpp)
#define HMSM_WIND_PROFILE_NONE 0u
#define HMSM_WIND_PROFILE_CONSTANT 1u
#define HMSM_WIND_PROFILE_Y1 2u
#define HMSM_WIND_PROFILE_Y2 3u
#define HMSM_WIND_PROFILE_Y3 4u
#define HMSM_WIND_PROFILE_Y4 5u
#define HMSM_WIND_PROFILE_TURBULENT 6u
#define HMSM_WIND_PROFILE_ATMOSPHERIC 7u

/// The ping-pong halves of chain_rotation and chain_origin: pointer-jumping round r reads half
/// HMSM_HALF_READ(r) (unused in round 0) and writes half HMSM_HALF_WRITTEN(r), so after `rounds`
/// rounds the pose is in half HMSM_FINAL_HALF(rounds), which level by level writes in place.
#define HMSM_HALF_READ(round) (((round) + 1u) & 1u)
#define HMSM_HALF_WRITTEN(round) ((round) & 1u)
#define HMSM_FINAL_HALF(rounds) (((rounds) - 1u) & 1u)

/// What a dispatch runs: PassConstants.kind (hmsm::detail::DispatchKind, src/pass_table.h, lists
/// the same numbers). PassConstants.round means only what JUMP_ROUND and
/// JUMP_ROUNDS_IN_DISPATCH say; every other kind leaves it 0.
/// PER_ELEMENT: a flat pass (wind_force, integrate, node_relative, node_world), thread i on
///   element i of the pass's domain.
/// JUMP_ROUND: compose or root_positions, the pointer-jumping round PassConstants.round: chain c
///   combines with its 2^round-th ancestor (chain_jump), reading half src_half (unused in round
///   0) and writing half dst_half.
/// JUMP_ROUNDS_IN_DISPATCH: compose or root_positions, every round in one dispatch: one
///   workgroup per instance of the group loops over the instance's chains, round after round,
///   with a workgroup barrier between rounds (PassConstants.round holds the number of rounds;
///   round r reads half HMSM_HALF_READ(r) and writes half HMSM_HALF_WRITTEN(r)). Its workgroups
///   have a power-of-two size from 64 to HMSM_MAX_ROUNDS_WORKGROUP_SIZE
///   (hmsm::gpu::rounds_workgroup_size).
/// LEVEL: compose or root_positions for the chains of one depth level (level_begin,
///   level_count per instance), in place in half dst_half.
/// INSTANCE_SWEEP: integrate under the articulated exchange (PassConstants.dynamics
///   HMSM_PASS_DYNAMICS_ARTICULATED): one workgroup per instance (of
///   hmsm::gpu::sweep_workgroup_size invocations) sweeps its chains depth by depth, up from the
///   deepest and then down from the trunk, with a workgroup barrier between depths, then steps
///   each joint (src/common/articulated_math.h).
/// Composition::path_walk runs a pass that leads a walk (the pass table's `walk` column) and its
/// walk partner in one dispatch, thread i handling element i of the leader's domain:
/// WIND_PAIR: wind_force then integrate for chain i (only the new angles are stored); under
///   the articulated exchange wind_force alone (an INSTANCE_SWEEP integrate follows).
/// POSE_WALK: compose then root_positions for chain i by the top-down walk (its ancestors from
///   the trunk down: R = R_parent T, O = O_parent + R_parent l_attach, written to the joint
///   matrix), the ancestors gathered by following chain_parent up.
/// POSE_WALK_FROM_RECORDS: the same, the ancestors and attach nodes read whole from the walk
///   records (beyond HMSM_WALK_PATH_CAPACITY through chain_jump and chain_attach).
/// NODE_PAIR: node_relative then node_world for node i.
/// The walk that integrates ahead (CUDA forests; docs/cuda.md), two compose dispatches:
/// WALK_TOP_POSES: one thread per chain of depth 0 to the model's top depth (the first
///   level_count model chains; at least depth 0 and 1: step_program.h walk_top_depth) walks the
///   pose from the angles of chain_state and stores it to half src_half of chain_rotation and
///   chain_origin; the trunk's thread also stores the wind scale lambda_i Y
///   of the next step (wind-table slot wind_slot + 1) of its instance in the w of its chain_origin.
/// WALK_AHEAD: every chain walks from the stored pose of its nearest ancestor among the top
///   chains (its own if it is one; level_count as for WALK_TOP_POSES), writes its joint matrix,
///   then runs the next step's wind_force and integrate with that pose and Y, writing
///   the next angles to a second state buffer.
/// CONTOUR_SEPARATE: contour writing vertex_position (x, y, z, 1) and vertex_normal
///   (nx, ny, nz, 0), thread i on vertex i.
/// CONTOUR_PACKED: contour writing only vertex_position, its w the bits of the octahedral normal
///   word (src/common/octahedral.h); a thread per model vertex and group of
///   HMSM_PACKED_CONTOUR_INSTANCES instances (below).
#define HMSM_DISPATCH_PER_ELEMENT 0u
#define HMSM_DISPATCH_JUMP_ROUND 1u
#define HMSM_DISPATCH_JUMP_ROUNDS_IN_DISPATCH 2u
#define HMSM_DISPATCH_LEVEL 3u
#define HMSM_DISPATCH_WIND_PAIR 4u
#define HMSM_DISPATCH_POSE_WALK 5u
#define HMSM_DISPATCH_POSE_WALK_FROM_RECORDS 6u
#define HMSM_DISPATCH_NODE_PAIR 7u
#define HMSM_DISPATCH_WALK_TOP_POSES 8u
#define HMSM_DISPATCH_WALK_AHEAD 9u
#define HMSM_DISPATCH_CONTOUR_SEPARATE 10u
#define HMSM_DISPATCH_CONTOUR_PACKED 11u
#define HMSM_DISPATCH_INSTANCE_SWEEP 12u
#define HMSM_DISPATCH_KIND_COUNT 13u
#define HMSM_MAX_ROUNDS_WORKGROUP_SIZE 1024
/// A chain's walk record (binding HMSM_BINDING_CHAIN_WALK, static, model-local indices): int 0
/// its depth d; int u, 1 <= u <= HMSM_WALK_PATH_CAPACITY, its ancestor u levels up (-1 past the
/// trunk); int HMSM_WALK_ATTACH(u), 0 <= u < HMSM_WALK_ATTACH_CAPACITY, the attach node of the chain
/// u levels up (u = 0:
/// the chain itself; -1 for the trunk and past it). With the whole path in one 128-byte record a
/// walk thread makes one round of loads for its ancestors and their attach nodes, where
/// following chain_parent up takes one dependent load per level.
#define HMSM_WALK_RECORD_INTS 32u
#define HMSM_WALK_PATH_CAPACITY 15u
/// Index in the record of the attach node of the chain u levels up (u < HMSM_WALK_ATTACH_CAPACITY).
#define HMSM_WALK_ATTACH_CAPACITY 16u
#define HMSM_WALK_ATTACH(u) (HMSM_WALK_ATTACH_CAPACITY + (u))

/// A packed contour dispatch runs one thread per model vertex and group of this many consecutive
/// group instances (the last group may be short): the thread reads the vertex's model-scope
/// inputs once and places it in each instance of its group. Thread w handles model vertex
/// w % model_vertex_count of group w / model_vertex_count. A separate one maps thread i to
/// element i like every other dispatch.
#define HMSM_PACKED_CONTOUR_INSTANCES 8u

#ifdef __cplusplus
#include "host_device.h"

#include <cstddef>
#include <cstdint>
namespace hmsm::gpu {
using uint = uint32_t;
struct alignas(16) vec4 {
    float x, y, z, w;
};
#endif

/// Push constants of one dispatch (<= 128 bytes, std430). One dispatch covers one instance
/// group: a run of consecutive instances of the same model. Thread i of a dispatch handles
/// element (i % per_instance) of instance (i / per_instance) of the group, where per_instance is
/// model_chain_count, model_node_count, model_vertex_count, or level_count for a LEVEL or
/// WALK_TOP_POSES dispatch. `kind` (HMSM_DISPATCH_*) says what the dispatch runs.
///
/// A listed dispatch (instance_list = 1) covers instances of one model wherever they lie: its
/// group instance k is entry instance_begin + k of the instance table (binding
/// HMSM_BINDING_INSTANCE_TABLE), which gives that instance's first state chain, node and vertex
/// and its index; chain_begin, node_begin and vertex_begin are unused, and listed_threads is
/// per_instance. Kernels rebase such a dispatch to one instance per thread
/// (listed_instance_constants) and then run as for a group of one.
struct PassConstants {
    uint element_count;       // threads: group instances x per_instance
    uint instance_begin;      // first global instance of the group
    uint chain_begin;         // first state chain of the group
    uint node_begin;          // first state node of the group
    uint vertex_begin;        // first state vertex of the group
    uint model_chain_begin;   // first static chain of the group's model
    uint model_node_begin;    // first static node of the model
    uint model_vertex_begin;  // first static vertex of the model
    uint model_chain_count;   // chains per instance
    uint model_node_count;    // nodes per instance
    uint model_vertex_count;  // vertices per instance
    uint level_begin;         // level-by-level: first model chain of the level
    uint level_count;         // level-by-level: chains per instance in the level
    uint round;               // JUMP_ROUND: round r reads the 2^r-th ancestor (chain_jump); JUMP_ROUNDS_IN_DISPATCH: number of rounds; else 0
    uint kind;                // HMSM_DISPATCH_*: what the dispatch runs
    uint profile;             // hmsm::WindProfile value
    uint total_chains;        // allocated state chains: the stride between ping-pong halves
    uint total_model_chains;  // static chains of the scene: stride between chain_jump rounds
    uint src_half;            // ping-pong: half read (pose readers: the half holding R and O)
    uint dst_half;            // ping-pong: half written
    uint wind_slot;           // the step's wind-table slot (Backend::run sets it where reads_wind_slot)
    uint dynamics;            // HMSM_DYNAMICS_*: the equations wind_force and integrate run
    uint instance_list;       // 1: a listed dispatch (above), whose instances the instance table gives
    uint listed_threads;      // listed dispatch: threads per instance (per_instance); else 0
    vec4 params;              // (dt, max_angle, fix_weight, covers paused: 1 if the group has paused instances)
};

#ifdef __cplusplus
static_assert(sizeof(PassConstants) == 112, "PassConstants must match std430");
static_assert(offsetof(PassConstants, wind_slot) == 80 && offsetof(PassConstants, dynamics) == 84 &&
                  offsetof(PassConstants, params) == 96,
              "PassConstants must match std430");
static_assert(offsetof(PassConstants, round) == 52 && offsetof(PassConstants, kind) == 56,
              "PassConstants must match std430");
static_assert(sizeof(PassConstants) <= 128, "push constants must fit the guaranteed 128 bytes");

/// Threads of a packed contour dispatch (HMSM_PACKED_CONTOUR_INSTANCES): one per model vertex
/// and group of instances (a listed dispatch: one per vertex of each instance). Host and
/// device: the launchers size their grids by it and the CUDA kernel bounds its loop by it.
HMSM_HOST_DEVICE constexpr uint64_t packed_contour_threads(const PassConstants& pc) {
    if (pc.instance_list != 0) return pc.element_count;  // listed: one thread per vertex of each instance
    const uint32_t instances = pc.element_count / pc.model_vertex_count;
    return uint64_t((instances + HMSM_PACKED_CONTOUR_INSTANCES - 1) / HMSM_PACKED_CONTOUR_INSTANCES) *
           pc.model_vertex_count;
}

/// Workgroup size of an in-dispatch pointer-jumping dispatch over `chains` chains per instance:
/// the smallest power of two from 64 to HMSM_MAX_ROUNDS_WORKGROUP_SIZE that is >= `chains`
/// (or the maximum).
constexpr uint32_t rounds_workgroup_size(uint32_t chains) {
    uint32_t size = 64;
    while (size < chains && size < HMSM_MAX_ROUNDS_WORKGROUP_SIZE) size *= 2;
    return size;
}

/// Workgroup size of an INSTANCE_SWEEP dispatch over `instances` instances of `chains` chains
/// each: a forest's instances fill the device in workgroups of HMSM_WORKGROUP_SIZE, which keep
/// most of their invocations busy at every depth; fewer than HMSM_SWEEP_WIDE_BELOW instances
/// take a power of two from 64 to HMSM_MAX_SWEEP_WORKGROUP_SIZE that is >= `chains` (or the
/// maximum), so that a wide depth is swept in one or two turns instead of many.
#define HMSM_SWEEP_WIDE_BELOW 256u
#define HMSM_MAX_SWEEP_WORKGROUP_SIZE 512u
constexpr uint32_t sweep_workgroup_size(uint32_t instances, uint32_t chains) {
    if (instances >= HMSM_SWEEP_WIDE_BELOW) return HMSM_WORKGROUP_SIZE;
    const uint32_t size = rounds_workgroup_size(chains);
    return size < HMSM_MAX_SWEEP_WORKGROUP_SIZE ? size : HMSM_MAX_SWEEP_WORKGROUP_SIZE;
}

}  // namespace hmsm::gpu
#endif

#endif  // HMSM_GPU_LAYOUT_H
