// The vocabulary a simulation is configured, driven and read with: the backend, composition,
// vertex layout and outputs of SimulationConfig, the outputs Simulation::read() returns and the
// force fields of live control. The runtime's internals include this header, not the façade
// <hmsm/simulation.h>.
#pragma once

#include <hmsm/export.h>

#include <hmsm/names.h>
#include <hmsm/options.h>
#include <hmsm/status.h>
#include <hmsm/types.h>

#include <cstdint>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

namespace hmsm {

/// `cpu` is the serial float reference (the paper's baseline); `cpu64` the double-precision
/// oracle; `cpu_parallel` (named "cpu-parallel") the float passes of `cpu` split over all host
/// threads, bitwise the results of `cpu`; `automatic` picks CUDA, then a Vulkan GPU, then
/// cpu-parallel where the host has more than one thread, else `cpu`.
enum class BackendKind { cpu, cpu64, vulkan, cuda, automatic, cpu_parallel };
inline constexpr NamedValue<BackendKind> kBackendKindNames[] = {
    {BackendKind::cpu, "cpu"},       {BackendKind::cpu64, "cpu64"}, {BackendKind::cpu_parallel, "cpu-parallel"},
    {BackendKind::vulkan, "vulkan"}, {BackendKind::cuda, "cuda"},   {BackendKind::automatic, "auto"},
};

HMSM_API const char* to_string(BackendKind kind);
HMSM_API std::optional<BackendKind> parse_backend_kind(std::string_view name);
/// Backends compiled into this build (never `automatic`).
HMSM_API std::vector<BackendKind> compiled_backends();

/// How passes 3 and 5 accumulate down the hierarchy. All give the same poses.
enum class Composition {
    /// The paper's pointer jumping in ceil(log2(D+1)) rounds. It chooses its dispatch form per
    /// instance group by size: every round in one dispatch per pass (one workgroup per instance
    /// runs round after round with a barrier in between) for 64 or more instances, or models of
    /// at most 512 chains (1,024 on Vulkan), else one dispatch per round over every chain of
    /// every instance; models of more than 16,384 chains always take one dispatch per round.
    pointer_jumping,
    /// One dispatch per depth level, D+1 in all (a reference for comparison).
    level_by_level,
    /// Passes 3 and 5 in one dispatch in which every chain walks its ancestors from the trunk
    /// down (R = R_parent T, O = O_parent + R_parent l_attach: level by level's poses bit for
    /// bit, depth-many products per chain, no dependent dispatch or barrier inside); passes 1
    /// and 2 then run in one dispatch per chain, and passes 4 and 6 in one per node after the
    /// walk: four dependent dispatches per step (two for joints only), the fewest of all
    /// compositions. Measured faster than pointer_jumping on an H100 (docs/benchmarks) for one
    /// tree and for forests, on CUDA and on Vulkan.
    path_walk,
    /// The default: the composition measured fastest on the backend the simulation runs on,
    /// `path_walk` on a GPU (CUDA, Vulkan on a GPU), `pointer_jumping` on the CPU backends and
    /// on Vulkan over a CPU driver (lavapipe), where the walk's depth-many products cost more
    /// than the rounds, and `pointer_jumping` on any backend for a hierarchy deeper than the
    /// walk's break-even depth (docs/architecture.md). Simulation::config() reports the
    /// composition it resolved to.
    automatic,
};
inline constexpr NamedValue<Composition> kCompositionNames[] = {
    {Composition::pointer_jumping, "pointer_jumping"},
    {Composition::level_by_level, "level_by_level"},
    {Composition::path_walk, "path_walk"},
    {Composition::automatic, "automatic"},
};
HMSM_API const char* to_string(Composition composition);
HMSM_API std::optional<Composition> parse_composition(std::string_view name);

/// How the contour pass stores the mesh vertices on the device (docs/formats.md, "Vertex
/// layouts"). Both give the same positions and Simulation::read() returns the same outputs.
/// - `separate`: vertex_position is (x, y, z, 1) and vertex_normal (nx, ny, nz, 0), float32 vec4
///   each: 32 bytes per vertex.
/// - `packed`: only vertex_position (x, y, z, w), 16 bytes per vertex. w holds, bit for bit, the
///   unit normal octahedral-encoded as two snorm16: GLSL `packSnorm2x16(oct_encode(n))`, read
///   back with `oct_decode(unpackSnorm2x16(floatBitsToUint(p.w)))` (oct_encode and oct_decode as
///   documented there; decoding error below 1e-4 rad). The vertex_normal buffer then has zero
///   elements and is never written; hmsm::vulkan::SharedBuffers and
///   hmsm::cuda::DeviceOutputs report the layout.
enum class VertexLayout { separate, packed };
inline constexpr NamedValue<VertexLayout> kVertexLayoutNames[] = {
    {VertexLayout::separate, "separate"}, {VertexLayout::packed, "packed"}};
HMSM_API const char* to_string(VertexLayout layout);
HMSM_API std::optional<VertexLayout> parse_vertex_layout(std::string_view name);

/// What a step produces (docs/model.md 3.10). An engine that skins its own mesh needs only the
/// joint matrices: passes 1-5. `joints_and_nodes` adds pass 6 (node positions), `all` pass 7
/// (mesh vertices and normals). Passes a step does not need are not dispatched at all and the
/// buffers of outputs not produced are not allocated; Simulation::read() of such an output
/// fails with invalid_argument. Chain rotations, origins, angles and joint matrices are always
/// produced. With `joints` the state holds, per model and level of detail, only the nodes the
/// passes read: each chain's attach node (node_relative's u, 16 bytes a node), not the whole
/// skeleton; Simulation::node_count() still counts the skeleton's nodes.
enum class Outputs { joints, joints_and_nodes, all };
inline constexpr NamedValue<Outputs> kOutputsNames[] = {
    {Outputs::joints, "joints"}, {Outputs::joints_and_nodes, "nodes"}, {Outputs::all, "all"}};
HMSM_API const char* to_string(Outputs outputs);
HMSM_API std::optional<Outputs> parse_outputs(std::string_view name);

/// Where the instances' chains, nodes and vertices lie in the state and output buffers
/// (docs/driving.md, streaming budgets). Simulation::read() returns the same outputs in both.
/// - `packed`: instance-major in index order, instance i's elements right behind those of
///   instance i - 1, as read() returns them and as the shared GPU buffers
///   (hmsm::vulkan::SharedBuffers, hmsm::cuda::DeviceOutputs) hold them. An add, a removal or a
///   level switch shifts the elements of every instance behind the first one it changes.
/// - `placed`: each instance keeps a slot of its own (Simulation::instance_placement) from the
///   add or level switch that gave it until it is removed or switches again; freed slots are
///   reused by later instances of the same model and level. Adds, swap removals and level
///   switches then move only the instances they touch; the shared buffers hold every slot
///   (free ones too: their counts are the elements held) and an engine finds an instance's
///   joints at its placement. Taken where the backend runs listed dispatches (cuda, vulkan);
///   elsewhere the layout stays packed and instance_placement reports the packed places.
enum class InstanceLayout { packed, placed };
inline constexpr NamedValue<InstanceLayout> kInstanceLayoutNames[] = {
    {InstanceLayout::packed, "packed"}, {InstanceLayout::placed, "placed"}};
HMSM_API const char* to_string(InstanceLayout layout);
HMSM_API std::optional<InstanceLayout> parse_instance_layout(std::string_view name);

struct SimulationConfig {
    BackendKind backend = BackendKind::automatic;
    ModelOptions model;
    Parameters parameters;
    Wind wind;
    Composition composition = Composition::automatic;
    /// The device layout of the mesh vertices; packed halves the bytes the contour pass writes.
    VertexLayout vertex_layout = VertexLayout::separate;
    /// Threads of the cpu-parallel backend (also when `automatic` picks it); 0: the
    /// environment variable HMSM_CPU_THREADS if set, else every hardware thread. At most 1024.
    uint32_t cpu_threads = 0;
    /// Collect per-pass device times (pass_times()). Off by default: timers serialize GPU work
    /// and keep CUDA from replaying a step as one graph.
    bool profile_passes = false;
    /// What each step produces; skipped passes cost nothing.
    Outputs outputs = Outputs::all;
    /// Where the instances' elements lie; `placed` for a streaming open world.
    InstanceLayout instance_layout = InstanceLayout::packed;
};

/// What a caller can read back. Components per element: positions and normals 3 (x, y, z),
/// chain rotations 9 (column-major), chain origins 3, chain angles 4 (theta_x, theta_z and
/// their rates), joint matrices 12: M_c = [R_c | O_c] row by row, (r00, r01, r02, ox, r10, r11,
/// r12, oy, r20, r21, r22, oz) with rIJ = row I, column J of R_c (docs/formats.md "Joint
/// matrices"; the GPU buffers store the same 12 floats per chain). Elements are instance-major;
/// nodes in input order, chains in chain order. vertex_normals are unit normals in both vertex
/// layouts (decoded from the positions' w when packed); vertex_positions are x, y, z in both.
enum class Output { node_positions, vertex_positions, vertex_normals, chain_rotations,
                    chain_origins, chain_angles, joint_matrices };
HMSM_API uint32_t output_components(Output output);

/// A sphere that pushes branches (docs/model.md 3.9): a character, a vehicle, an explosion. It
/// acts on every chain whose origin x lies within `radius` of `center` (world space, metres) with
/// weight h = max(0, 1 - |x - center| / radius)^2, in the units of wind strength, and is not
/// scaled by an instance's wind scale.
struct ForceField {
    enum class Kind : uint32_t { directional = 0, radial = 1 };
    Kind kind = Kind::directional;
    Vec3 center{0.0};
    double radius = 1.0;        ///< > 0
    Vec3 directional{0.0};      ///< kind directional: the force h * directional
    double radial = 0.0;        ///< kind radial: the force h * radial * unit(x - center)
};
/// At most this many force fields act at once.
inline constexpr uint32_t kMaxForceFields = 16;

/// Checks a force-field list (count; centre, radius and force within the ranges of
/// docs/model.md 3.11); the message names the field, the value and the limit.
HMSM_API Status validate_force_fields(std::span<const ForceField> fields);

}  // namespace hmsm
