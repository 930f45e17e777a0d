// The simulation: owns the state, the seven-pass sequence (written once, here) and a backend.
#pragma once

#include <hmsm/export.h>

#include <hmsm/hierarchy.h>
#include <hmsm/mesh.h>
#include <hmsm/options.h>
#include <hmsm/pass.h>
#include <hmsm/scene.h>

#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace hmsm {

/// `cpu` is the serial float reference (the paper's baseline); `cpu64` the double-precision
/// oracle; `cpu_parallel` (named "cpu-parallel") the float passes of `cpu` split over all host
/// threads, bitwise the results of `cpu`; `automatic` picks CUDA, then a Vulkan GPU, then
/// cpu-parallel where the host has more than one thread, else `cpu`.
enum class BackendKind { cpu, cpu64, vulkan, cuda, automatic, cpu_parallel };

HMSM_API const char* to_string(BackendKind kind);
HMSM_API std::optional<BackendKind> parse_backend_kind(std::string_view name);
/// Backends compiled into this build (never `automatic`).
HMSM_API std::vector<BackendKind> compiled_backends();

/// How passes 3 and 5 accumulate down the hierarchy. All give the same poses.
enum class Composition {
    /// The paper's pointer jumping in ceil(log2(D+1)) rounds, per instance group in one
    /// dispatch per pass (as pointer_jumping_in_dispatch) or one dispatch per round (as
    /// pointer_jumping_per_round), whichever measured faster: in one dispatch for 64 or more
    /// instances, or models of at most 512 chains (1,024 on Vulkan).
    pointer_jumping,
    /// Pointer jumping with one dispatch per round over every chain of every instance.
    pointer_jumping_per_round,
    /// Pointer jumping with every round in one dispatch per pass: one workgroup per instance
    /// runs round after round with a barrier in between (models of more than 16,384 chains
    /// still take one dispatch per round).
    pointer_jumping_in_dispatch,
    /// One dispatch per depth level, D+1 in all (for comparison).
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
    /// than the rounds. Simulation::config() reports the composition it resolved to.
    automatic,
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
HMSM_API const char* to_string(VertexLayout layout);
HMSM_API std::optional<VertexLayout> parse_vertex_layout(std::string_view name);

/// What a step produces (docs/model.md 3.10). An engine that skins its own mesh needs only the
/// joint matrices: passes 1-5. `joints_and_nodes` adds pass 6 (node positions), `all` pass 7
/// (mesh vertices and normals). Passes a step does not need are not dispatched at all and the
/// buffers of outputs not produced are not allocated; Simulation::read() of such an output
/// fails with invalid_argument. Chain rotations, origins, angles and joint matrices are always
/// produced.
enum class Outputs { joints, joints_and_nodes, all };
HMSM_API const char* to_string(Outputs outputs);
/// "joints", "nodes" (joints_and_nodes) or "all".
HMSM_API std::optional<Outputs> parse_outputs(std::string_view name);

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

/// Checks a force-field list (count, finite numbers, radius > 0); the message names the field.
HMSM_API Status validate_force_fields(std::span<const ForceField> fields);

/// A running simulation of a scene. Threading: one Simulation may be used by one thread at a
/// time (calls on it are not synchronized); distinct Simulations may run concurrently on any
/// backends, and may be created and destroyed from several threads at once. const member
/// functions, read() included, may run concurrently with each other but not with a non-const
/// call; concurrent read()s are serialized inside (docs/engine.md).
class HMSM_API Simulation {
public:
    /// Validates everything, builds hierarchies and meshes, creates the backend, uploads the
    /// scene and poses it at rest (S = V = 0).
    static Result<std::unique_ptr<Simulation>> create(const Scene& scene,
                                                      const SimulationConfig& config);
    ~Simulation();
    Simulation(const Simulation&) = delete;
    Simulation& operator=(const Simulation&) = delete;

    /// Advances `count` fixed time steps (the passes config().outputs needs). Blocks until done.
    Status step(uint32_t count = 1);

    uint64_t steps_done() const;
    /// Simulated seconds: steps_done() * dt.
    double time() const;

    // --- Live control (docs/model.md 3.9). Each call takes effect from the next step; the state
    // of every instance carries over unchanged. A rejected call changes nothing.

    /// Replaces the wind; its clock continues, so the change is phase-continuous.
    Status set_wind(const Wind& wind);
    /// The wind in force.
    const Wind& wind() const;
    /// Replaces the force-field list (at most kMaxForceFields; empty removes all).
    Status set_force_fields(std::span<const ForceField> fields);
    std::span<const ForceField> force_fields() const;
    /// Per instance (index into the current instance list): wind scale (>= 0), wind phase (in
    /// profile units) and the active flag. An inactive instance is frozen: its state and outputs
    /// stay as they are until it is activated again.
    Status set_instance_wind_scale(uint64_t instance, double wind_scale);
    Status set_instance_wind_phase(uint64_t instance, double wind_phase);
    Status set_instance_active(uint64_t instance, bool active);
    /// Appends instances of the scene's models; they start at rest (S = V = 0, posed at rest).
    /// Within the capacity the device buffers have (spare after removals or an earlier growth)
    /// this costs what the added instances cost; past it, the scene is uploaded anew once with
    /// 1.5 times the capacity (docs/driving.md).
    Status add_instances(std::span<const Instance> instances);
    /// Removes instances by their current indices (no repeats); the survivors keep their order
    /// and their state, moved on the device (docs/driving.md).
    Status remove_instances(std::span<const uint64_t> indices);
    /// The current instance list (models are those of the scene given to create()).
    std::span<const Instance> instances() const;

    /// Reads an output for every instance, converted to the requested precision.
    Status read(Output output, std::vector<float>& values) const;
    Status read(Output output, std::vector<double>& values) const;

    /// Device time per pass over the last step() call.
    PassTimes pass_times() const;

    BackendKind backend_kind() const;
    std::string device_name() const;
    const SimulationConfig& config() const;
    /// The scene as given to create() (its instance list does not follow live changes; see
    /// instances()).
    const Scene& scene() const;
    const Hierarchy& hierarchy(uint32_t model) const;
    const MeshTemplate& mesh(uint32_t model) const;

    uint64_t instance_count() const;
    uint64_t chain_count() const;   ///< over all instances
    uint64_t node_count() const;    ///< over all instances
    uint64_t vertex_count() const;  ///< over all instances
    uint32_t jump_rounds() const;   ///< pointer-jumping rounds of passes 3 and 5
    /// Chains whose inertia the frequency cap raised (docs/model.md 3.4), over all models, once
    /// per model.
    uint32_t capped_chain_count() const;

    /// Defined only inside the library (src/simulation_access.h), for hmsm's own interop code,
    /// tools and tests; incomplete everywhere else.
    struct Access;

private:
    struct Impl;
    explicit Simulation(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> impl_;
};

}  // namespace hmsm
