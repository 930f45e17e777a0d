// Shared by the seven passes: the layout header, push constants, every storage buffer of
// gpu_layout.h (binding = BufferId), the thread -> element mapping and the wind profiles.
// Every function here mirrors the CPU reference (src/cpu/cpu_state.h, src/common/wind_profile.h).
// Each .comp enables GL_GOOGLE_include_directive before including this file.
#ifndef HMSM_COMMON_GLSL
#define HMSM_COMMON_GLSL

#include "gpu_layout.h"
#include "run_table_layout.h"  // batched runs: the run table
#include "octahedral.glsl"  // oct_encode / oct_decode for VertexLayout::packed

#ifdef HMSM_SPECIALIZED_WORKGROUP_SIZE
// compose, root_positions and integrate: the size is specialization constant 0, set per pipeline
// (HMSM_WORKGROUP_SIZE, or gpu::rounds_workgroup_size for in-dispatch rounds,
// gpu::sweep_workgroup_size for instance sweeps).
layout(local_size_x_id = 0, local_size_y = 1, local_size_z = 1) in;
#else
layout(local_size_x = HMSM_WORKGROUP_SIZE, local_size_y = 1, local_size_z = 1) in;
#endif

// The ping-pong pose buffers are coherent where a workgroup reads, after a barrier, what other
// invocations of it wrote (in-dispatch pointer-jumping rounds).
#ifndef HMSM_POSE_COHERENCE
#define HMSM_POSE_COHERENCE
#endif
// The buffers where the articulated exchange's sweeps keep their scratch likewise (T, the loads
// and the force: integrate.comp).
#ifndef HMSM_SWEEP_COHERENCE
#define HMSM_SWEEP_COHERENCE
#endif

layout(push_constant, std430) uniform PushBlock {
    PassConstants pushed;
};
// The run table (run_table_layout.h): the constants of each dispatch of the
// batched runs of the step program, and the first workgroup of the launch that runs it.
layout(set = HMSM_RUN_TABLE_SET, binding = HMSM_RUN_TABLE_CONSTANTS, std430) readonly buffer RunConstants {
    PassConstants run_constants[];
};
layout(set = HMSM_RUN_TABLE_SET, binding = HMSM_RUN_TABLE_WORKGROUPS, std430) readonly buffer RunWorkgroups {
    uint run_first_workgroup[];
};

/// The constants of the dispatch this workgroup belongs to, whether it was launched alone (push
/// constants) or as part of a run (its run-table entry); set by load_constants().
PassConstants pc;
/// The launch's workgroup where the dispatch's workgroups begin (0 for a dispatch alone).
uint dispatch_first_workgroup = 0u;

/// The launch's workgroup index. The host spreads large launches over a 2-D grid of workgroups
/// (maxComputeWorkGroupCount[0] may be as low as 65535), so the index is linearized here.
uint launch_workgroup_index() { return gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x; }

/// Every main() starts here. A run's workgroups find their dispatch by a binary search for the
/// last entry of the run whose first workgroup is at most theirs (uniform per workgroup); the
/// step's wind slot comes with the push constants.
void load_constants() {
    if (pushed.kind != HMSM_DISPATCH_RUN_TABLE) {
        pc = pushed;
        return;
    }
    uint w = launch_workgroup_index();
    uint lo = pushed.instance_begin, hi = pushed.instance_begin + pushed.element_count - 1u;
    while (lo < hi) {
        uint mid = hi - (hi - lo) / 2u;
        if (run_first_workgroup[mid] <= w) lo = mid;
        else hi = mid - 1u;
    }
    pc = run_constants[lo];
    pc.wind_slot = pushed.wind_slot;
    dispatch_first_workgroup = run_first_workgroup[lo];
}

// Static data (model and instance scope), written only by uploads.
layout(set = 0, binding = HMSM_BINDING_CHAIN_PARENT, std430) readonly buffer ChainParent { int chain_parent[]; };
layout(set = 0, binding = HMSM_BINDING_CHAIN_JUMP, std430) readonly buffer ChainJump { int chain_jump[]; };
layout(set = 0, binding = HMSM_BINDING_CHAIN_ATTACH, std430) readonly buffer ChainAttach { int chain_attach[]; };
// HMSM_WALK_RECORD_INTS / 4 ivec4 per model chain: its walk record (gpu_layout.h).
layout(set = 0, binding = HMSM_BINDING_CHAIN_WALK, std430) readonly buffer ChainWalk { ivec4 chain_walk[]; };
layout(set = 0, binding = HMSM_BINDING_CHAIN_REST_ROTATION, std430) readonly buffer ChainRestRotation { mat3x4 chain_rest_rotation[]; };
layout(set = 0, binding = HMSM_BINDING_CHAIN_CONSTANTS, std430) readonly buffer ChainConstants { vec4 chain_constants[]; };
layout(set = 0, binding = HMSM_BINDING_NODE_OWNER, std430) readonly buffer NodeOwner { int node_owner[]; };
layout(set = 0, binding = HMSM_BINDING_NODE_LOCAL, std430) readonly buffer NodeLocal { vec4 node_local[]; };
layout(set = 0, binding = HMSM_BINDING_VERTEX_CHAIN, std430) readonly buffer VertexChain { ivec2 vertex_chain[]; };
layout(set = 0, binding = HMSM_BINDING_VERTEX_REST_POSITION, std430) readonly buffer VertexRestPosition { vec4 vertex_rest_position[]; };
layout(set = 0, binding = HMSM_BINDING_VERTEX_REST_NORMAL, std430) readonly buffer VertexRestNormal { vec4 vertex_rest_normal[]; };
layout(set = 0, binding = HMSM_BINDING_VERTEX_PARENT_POSITION, std430) readonly buffer VertexParentPosition { vec4 vertex_parent_position[]; };
layout(set = 0, binding = HMSM_BINDING_VERTEX_PARENT_NORMAL, std430) readonly buffer VertexParentNormal { vec4 vertex_parent_normal[]; };
layout(set = 0, binding = HMSM_BINDING_INSTANCE_ORIGIN, std430) readonly buffer InstanceOrigin { vec4 instance_origin[]; };
layout(set = 0, binding = HMSM_BINDING_INSTANCE_YAW, std430) readonly buffer InstanceYaw { vec4 instance_yaw[]; };

// State, one element per chain/node/vertex of every instance (ping-pong: two halves).
layout(set = 0, binding = HMSM_BINDING_CHAIN_STATE, std430) buffer ChainState { vec4 chain_state[]; };
layout(set = 0, binding = HMSM_BINDING_CHAIN_FORCE, std430) HMSM_SWEEP_COHERENCE buffer ChainForce { vec2 chain_force[]; };
layout(set = 0, binding = HMSM_BINDING_CHAIN_LOCAL, std430) HMSM_SWEEP_COHERENCE buffer ChainLocal { mat3x4 chain_local[]; };
layout(set = 0, binding = HMSM_BINDING_CHAIN_ROTATION, std430) HMSM_POSE_COHERENCE buffer ChainRotation { mat3x4 chain_rotation[]; };
layout(set = 0, binding = HMSM_BINDING_NODE_RELATIVE, std430) buffer NodeRelative { vec4 node_relative[]; };
layout(set = 0, binding = HMSM_BINDING_CHAIN_ORIGIN, std430) HMSM_POSE_COHERENCE buffer ChainOrigin { vec4 chain_origin[]; };
layout(set = 0, binding = HMSM_BINDING_NODE_WORLD, std430) buffer NodeWorld { vec4 node_world[]; };
layout(set = 0, binding = HMSM_BINDING_VERTEX_POSITION, std430) buffer VertexPosition { vec4 vertex_position[]; };
layout(set = 0, binding = HMSM_BINDING_VERTEX_NORMAL, std430) buffer VertexNormal { vec4 vertex_normal[]; };
// Joint matrices [R_c | O_c] as three vec4 rows (R row i, O_i); a mat3x4 whose "columns" are rows.
layout(set = 0, binding = HMSM_BINDING_JOINT_MATRIX, std430) buffer JointMatrix { mat3x4 joint_matrix[]; };

// The coupled dynamics (docs/model.md 3.13; no elements under the paper's): HMSM_CHAIN_DYNAMICS_VEC4S
// vec4 per model chain (its record), and per chain the load g of its last step; under the
// articulated exchange HMSM_CHAIN_ARTICULATED_VEC4S vec4 per model chain, and the loads' place
// holds scratch of the sweeps (gpu_layout.h).
layout(set = 0, binding = HMSM_BINDING_CHAIN_DYNAMICS, std430) readonly buffer ChainDynamics { vec4 chain_dynamics[]; };
layout(set = 0, binding = HMSM_BINDING_CHAIN_LOAD, std430) HMSM_SWEEP_COHERENCE buffer ChainLoad { vec2 chain_load[]; };

// Live control, written by the host between steps (gpu_layout.h): 9 vec4 per instance, and the
// wind table (turbulent amplitudes, wind vector, force fields, per-step slots).
layout(set = 0, binding = HMSM_BINDING_INSTANCE_WIND, std430) readonly buffer InstanceWind { vec4 instance_wind[]; };
layout(set = 0, binding = HMSM_BINDING_WIND_TABLE, std430) readonly buffer WindTable { vec4 wind_table[]; };
// Listed dispatches (PassConstants.instance_list): per entry (chain_begin, node_begin,
// vertex_begin, instance) of one listed instance.
layout(set = 0, binding = HMSM_BINDING_INSTANCE_TABLE, std430) readonly buffer InstanceTable { uvec4 instance_table[]; };

/// A listed dispatch's constants for its group instance k (src/common/element_index.h
/// listed_instance_constants): the dispatch over that instance alone.
void rebase_to_listed_instance(uint k) {
    uvec4 entry = instance_table[pc.instance_begin + k];
    pc.chain_begin = entry.x;
    pc.node_begin = entry.y;
    pc.vertex_begin = entry.z;
    pc.instance_begin = entry.w;
    pc.element_count = pc.listed_threads;
    pc.instance_list = 0u;
    pc.params.w = 0.0;
}

/// Whether group instance k is paused (inactive, frozen): a dispatch may cover paused instances
/// between active ones (it says so in params.w) and skips their elements (the z of the
/// instance's first instance_wind element; kernels/cuda/pass_math.cuh instance_paused).
bool instance_paused(uint k) {
    return pc.params.w != 0.0 && instance_wind[HMSM_INSTANCE_WIND_VEC4S * (pc.instance_begin + k)].z != 0.0;
}

/// The workgroup's index within its dispatch, and the global thread index of the dispatch.
uint workgroup_index() { return launch_workgroup_index() - dispatch_first_workgroup; }
/// In a listed dispatch, thread t is thread t % listed_threads of its listed instance: pc is
/// rebased to that instance (rebase_to_listed_instance) and the index within it returned; a
/// thread past the dispatch gets an index past the rebased element_count.
uint thread_index() {
    uint t = workgroup_index() * gl_WorkGroupSize.x + gl_LocalInvocationID.x;
    if (pc.instance_list == 0u) return t;
    if (t >= pc.element_count) return 0xFFFFFFFFu;
    uint k = t / pc.listed_threads;
    rebase_to_listed_instance(k);
    return t - k * pc.element_count;
}
/// The group instance of an in-dispatch rounds workgroup (one workgroup per instance): its
/// workgroup index, or in a listed dispatch 0 after rebasing pc to that instance (a workgroup
/// past the dispatch gets an index past the rebased dispatch's one instance). Uniform per
/// workgroup.
uint rounds_instance() {
    uint k = workgroup_index();
    if (pc.instance_list == 0u) return k;
    if (k >= pc.element_count / pc.model_chain_count) return 0xFFFFFFFFu;
    rebase_to_listed_instance(k);
    return 0u;
}

/// State index of model chain `c` of group instance `k` (cpu_state.h state_chain).
uint state_chain(uint k, uint c) { return pc.chain_begin + k * pc.model_chain_count + c; }
/// State index of model node `n` of group instance `k` (cpu_state.h state_node).
uint state_node(uint k, uint n) { return pc.node_begin + k * pc.model_node_count + n; }

/// Offset of a ping-pong half in chain_rotation / chain_origin.
uint half_offset(uint which) { return which * pc.total_chains; }

/// A 3x3 matrix stored as three vec4 columns (w = 0).
mat3 as_mat3(mat3x4 m) { return mat3(m[0].xyz, m[1].xyz, m[2].xyz); }
/// The pose a joint matrix holds (rows: R row i, O_i; written by pass 5 in every composition).
mat3 joint_rotation(mat3x4 j) { return transpose(mat3(j[0].xyz, j[1].xyz, j[2].xyz)); }
vec3 joint_origin(mat3x4 j) { return vec3(j[0].w, j[1].w, j[2].w); }
mat3x4 as_mat3x4(mat3 m) { return mat3x4(vec4(m[0], 0.0), vec4(m[1], 0.0), vec4(m[2], 0.0)); }

const float HMSM_PI = 3.14159265358979323846;

// sin(pi x) and cos(pi x) with the argument first reduced to [-1, 1): GPU sin/cos are only
// accurate near [-pi, pi], and the profiles reach 25 pi x with x up to 4.
float sinpi(float x) { return sin(HMSM_PI * (x - 2.0 * floor(0.5 * x + 0.5))); }
float cospi(float x) { return cos(HMSM_PI * (x - 2.0 * floor(0.5 * x + 0.5))); }

/// Y(x) of docs/model.md 3.5 (src/common/wind_profile.h); profile = hmsm::WindProfile value.
float wind_profile_y(uint profile, float x) {
    switch (profile) {
        case HMSM_WIND_PROFILE_CONSTANT: return 1.0;
        case HMSM_WIND_PROFILE_Y1:
            return cospi(x) * cospi(3.0 * x) * cospi(5.0 * x) * cospi(7.0 * x) - 0.1 * sinpi(25.0 * x);
        case HMSM_WIND_PROFILE_Y2:
            return (sinpi(x) + sinpi(3.0 * x) + sinpi(5.0 * x) + sinpi(7.0 * x)) / 4.0;
        case HMSM_WIND_PROFILE_Y3: {
            float c = cospi(x);
            return c * c * cospi(3.0 * x) * cospi(5.0 * x) - 0.02 * sinpi(25.0 * x);
        }
        case HMSM_WIND_PROFILE_Y4: {
            float c = cospi(x);
            return c * c * cospi(3.0 * x) * cospi(5.0 * x) - 0.1 * sinpi(25.0 * x);
        }
        default: return 0.0;  // none
    }
}

#endif  // HMSM_COMMON_GLSL
