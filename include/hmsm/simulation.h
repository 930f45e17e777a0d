// The simulation: owns the state, the seven-pass sequence (written once, here) and a backend.
// Its configuration vocabulary (SimulationConfig, BackendKind, Output, ForceField, ...) is
// <hmsm/config.h>, included here.
#pragma once

#include <hmsm/export.h>

#include <hmsm/config.h>
#include <hmsm/hierarchy.h>
#include <hmsm/mesh.h>
#include <hmsm/pass.h>
#include <hmsm/scene.h>

#include <memory>
#include <span>
#include <string>
#include <vector>

namespace hmsm {

/// A handle of one instance of a simulation, stable while it lives: the instances given to
/// create() get 0 .. n-1 in scene order, every added instance the next unused value. Removing
/// other instances leaves it valid; a removed instance's id is never given again in the
/// simulation's life (docs/driving.md, instance handles).
enum class InstanceId : uint64_t {};

/// Where an instance's elements begin in the state and output buffers (element indices:
/// chains, nodes as the simulation keeps them, mesh vertices), Simulation::instance_placement.
struct InstancePlacement {
    uint64_t first_chain = 0, first_node = 0, first_vertex = 0;
};

/// Distance bands for Simulation::update_lod (docs/driving.md, levels of detail): an instance
/// at distance d (metres, from its origin to the viewer) belongs on level k where
/// edges[k - 1] <= d < edges[k] (level 0 nearer than edges[0]; levels past a model's last are
/// its last). It leaves its level only once d passes the band's edge by more than
/// `hysteresis` times that edge, so a viewer oscillating about an edge does not flip it.
///
/// Coarsening by the bands fades (docs/model.md 3.12, fading to a coarser level): the instance
/// keeps its level while the chains the coarser level folds relax to rest relative to their
/// parents over `fade_steps` steps (on the backend, in each step), and it switches then; an
/// instance whose switch would move no vertex by more than `fade_bound_m` (at rest) switches
/// at the request (measured with a read of its state, which waits for the device; not on a
/// Vulkan simulation that an engine drives with record_steps, where it fades too).
/// fade_bound_m 0 reads nothing and fades every coarsening: for worlds in wind, where hardly
/// a tree is ever at rest. fade_steps 0 switches at once (the folded branches' deflection
/// vanishes in one frame). Refining always switches at once.
struct LodBands {
    std::vector<double> edges;  ///< strictly increasing, finite, > 0 (metres); empty: level 0
    double hysteresis = 0.1;    ///< fraction of an edge, in [0, 1)
    uint32_t fade_steps = 60;   ///< steps a coarsening fade takes, 0 to kMaxLodFadeSteps
    double fade_bound_m = 1e-3; ///< deflection (metres) that switches at the request, in [0, 1]; 0: none
};
/// The longest fade LodBands::fade_steps may ask for (about 10 minutes at the default dt).
inline constexpr uint32_t kMaxLodFadeSteps = 1u << 16;

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
    /// Per instance (index into the current instance list): wind scale (0 to 1e6, and the
    /// chains' wind force A s lambda at most 1e30: docs/model.md 3.11), wind phase (in profile
    /// units) and the active flag. An inactive instance is frozen: its state and outputs
    /// stay as they are until it is activated again.
    Status set_instance_wind_scale(uint64_t instance, double wind_scale);
    Status set_instance_wind_phase(uint64_t instance, double wind_phase);
    Status set_instance_active(uint64_t instance, bool active);
    /// Appends instances of the scene's models; they start at rest (S = V = 0, posed at rest).
    /// Within the capacity the device buffers have (spare after removals or an earlier growth)
    /// this costs what the added instances cost; past it, the capacity first grows once to 1.5
    /// times, the live state copied into larger buffers on the device (docs/driving.md).
    Status add_instances(std::span<const Instance> instances);
    /// Makes room on the device for `count` instances in all, each as large as the scene's
    /// largest model, so that adding up to that many costs only what the added instances cost:
    /// one growth of the capacity now if the room is smaller, nothing otherwise. The room is
    /// kept when a later addition outgrows it. At most kMaxInstances (docs/driving.md).
    Status reserve_instances(uint64_t count);
    /// The same for a world of levels of detail: room for `per_level[k]` instances at level k
    /// (finest first, Scene::lod_budgets; level k of each scene model that has it, the room of
    /// the largest), and for one template of every level, which the level switches of the GPU
    /// backends stage, so that adding up to that many instances and switching them among those
    /// levels costs only what the changes touch. Room for every instance at its full level, as
    /// reserve_instances(count) gives, is often tens of times larger. Count an instance fading
    /// to a coarser level at its finer level too (it runs both until the fade ends), and on the
    /// CPU backends the instances one switch moves (their state is staged above the others).
    /// Fails with invalid_argument for no counts or more counts than the scene's models have
    /// levels, and with unsupported past kMaxInstances in all or past the largest buffer;
    /// nothing changes then (docs/driving.md, streaming budgets).
    Status reserve_instances(std::span<const uint64_t> per_level);
    /// As add_instances(instances), and `ids` (as many as `instances`) receives the added
    /// instances' handles, in order.
    Status add_instances(std::span<const Instance> instances, std::span<InstanceId> ids);
    /// Removes instances by their current indices (no repeats); the survivors keep their order
    /// and their state, moved on the device (docs/driving.md).
    Status remove_instances(std::span<const uint64_t> indices);
    /// remove_instances() by handle: an id that was removed, was never given, or is listed
    /// twice is refused, naming it, and nothing changes.
    Status remove_instances_by_id(std::span<const InstanceId> ids);
    /// Removes instances by handle without keeping the order (docs/model.md 3.9, swap removal):
    /// the holes the removed instances leave below the new count are filled, lowest first, by
    /// the last surviving instances of the list, so that only as many instances move as are
    /// removed; every other survivor keeps its index. Handles stay valid (index_of follows the
    /// moved instances). Refuses what remove_instances_by_id() refuses, changing nothing.
    Status swap_remove_instances(std::span<const InstanceId> ids);
    /// The current index of the instance `id` (an error naming the id if it was removed or
    /// never given).
    Result<uint64_t> index_of(InstanceId id) const;
    /// The handle of the instance at current index `index` (an error if out of range).
    Result<InstanceId> id_of(uint64_t index) const;
    /// Where instance `id`'s elements lie in the state and output buffers (its first chain,
    /// node and vertex; SimulationConfig::instance_layout): in the placed layout its slot, which
    /// changes only when it switches level, else its running sums in the packed layout. An
    /// engine skinning from a shared GPU buffer (hmsm::vulkan::SharedBuffers,
    /// hmsm::cuda::DeviceOutputs) reads the instance's joint matrices from first_chain on.
    /// An error naming the id if it was removed or never given.
    Result<InstancePlacement> instance_placement(InstanceId id) const;
    /// The handles of the current instance list, index for index (ascending until a
    /// swap_remove_instances() moves an instance down).
    std::span<const InstanceId> instance_ids() const;
    /// Puts instances (current indices, no repeats) back at rest, exactly as right after
    /// add_instances(): S = V = 0, generalized force 0, posed at rest, whatever their state was
    /// (violent motion, or NaN from the caller's own numbers). Their settings (origin, wind
    /// scale and phase, active flag) and every other instance are untouched; a paused instance
    /// is reset and stays paused. Takes effect at once (read() returns the rest pose) and costs
    /// one rest pose of the listed instances. An index out of range or listed twice is refused
    /// and changes nothing. Threading as every non-const member (see the class comment).
    Status reset_instances(std::span<const uint32_t> indices);
    // --- Levels of detail at run time (docs/driving.md). Scene::lod_budgets gives each model
    // its levels: 0 is the model as created, higher levels are coarser. A switch runs the
    // instance on the level's model and keeps its handle, index, origin, yaw, wind scale and
    // phase and active flag; the chains both levels keep carry their angles, rates, force and
    // load, chains the finer level unfolds start rigid with their parent (angles and rates 0).
    // set_instance_lod(s) take effect at once (read() returns the new level's pose, the same for
    // kept chains) and end the listed instances' fades; request_instance_lods and update_lod
    // fade to coarser levels (LodBands): each step of the backend relaxes the folded chains of
    // the fading instances that are active (recorded and enqueued steps too), and a fade that
    // ended switches at the next step(), update_lod() or request_instance_lods().
    // Many switches in one call cost one reshape of the state from the first switched
    // instance on. A rejected call (an unknown handle, a level the model lacks, a handle
    // listed twice) changes nothing. Threading as every non-const member.

    /// Runs instance `id` on `level` (0 .. lod_level_count(model) - 1).
    Status set_instance_lod(InstanceId id, uint32_t level);
    /// set_instance_lod for each pair (`ids` and `levels` of one length), in one reshape.
    Status set_instance_lods(std::span<const InstanceId> ids, std::span<const uint32_t> levels);
    /// The level instance `id` runs on.
    Result<uint32_t> instance_lod(InstanceId id) const;
    /// Asks for `levels` (one per id, as set_instance_lods) with the bands' fade: a finer or
    /// equal level is taken at once (ending a fade), a coarser one fades (LodBands) unless the
    /// deflection to remove is within fade_bound_m already. Returns how many instances changed
    /// level or target. A rejected call changes nothing.
    Result<uint64_t> request_instance_lods(std::span<const InstanceId> ids, std::span<const uint32_t> levels);
    /// The level instance `id` is heading for: instance_lod(id) unless it is fading.
    Result<uint32_t> instance_lod_target(InstanceId id) const;
    /// Instances fading to a coarser level now.
    uint64_t fading_instance_count() const;
    /// Levels of scene model `model` (1 + Scene::lod_budgets[model].size()); 0 for no such model.
    uint32_t lod_level_count(uint32_t model) const;
    /// The bands update_lod() chooses by; invalid bands are refused and change nothing.
    Status set_lod_bands(const LodBands& bands);
    const LodBands& lod_bands() const;
    /// Chooses each instance's level from its distance to `viewer` (world metres) by the
    /// bands, with hysteresis (from the level a fading instance heads for), and asks for the
    /// changes in one request_instance_lods call: finer levels at once, coarser ones by a
    /// fade. Fades that ended since switch in the same reshape of the state as the call's
    /// changes (an instance both ending its fade and changing level switches to its fade's
    /// target first). Once per frame, before step().
    /// Returns how many instances changed level or target.
    Result<uint64_t> update_lod(Vec3 viewer);

    /// The current instance list. An instance on level 0 names its scene model; on a level
    /// k >= 1, `model` is the run model of that level (scene().models.size() or more), whose
    /// hierarchy() and mesh() describe what the instance runs.
    std::span<const Instance> instances() const;

    /// Reads an output for every instance, converted to the requested precision.
    Status read(Output output, std::vector<float>& values) const;
    Status read(Output output, std::vector<double>& values) const;

    /// Asynchronous readback, for a frame loop that should not wait for the copy: request_read
    /// starts copying `output` as the steps so far leave it and returns at once; take_read, in
    /// this frame or a later one, waits for that copy (if it has not finished) and returns the
    /// values read() would have returned at the request, whatever ran since (steps, live
    /// changes, instances added or removed: the values keep the request's instance list). A
    /// request stays until the next request_read of the same output, so take_read may be
    /// called again for the same values; each output has its own request. CUDA copies into
    /// pinned host memory the simulation keeps (grown to the largest request) with one
    /// device-to-host copy on its stream; the other backends read at the request. Threading:
    /// as step() (non-const: not concurrent with any other call on this simulation). Units and
    /// layout as read(). take_read without a request is invalid_argument.
    Status request_read(Output output);
    Status take_read(Output output, std::vector<float>& values);
    Status take_read(Output output, std::vector<double>& values);

    /// Device time per pass over the last step() call.
    PassTimes pass_times() const;

    BackendKind backend_kind() const;
    std::string device_name() const;
    const SimulationConfig& config() const;
    /// The scene as given to create() (its instance list does not follow live changes; see
    /// instances()).
    const Scene& scene() const;
    /// The hierarchy and mesh a model runs with: a scene model, or a run model of a level
    /// (instances()[i].model; lod_model()).
    const Hierarchy& hierarchy(uint32_t model) const;
    const MeshTemplate& mesh(uint32_t model) const;
    /// The run model of scene model `model` on `level` (an error naming both if absent).
    Result<uint32_t> lod_model(uint32_t model, uint32_t level) const;

    uint64_t instance_count() const;
    uint64_t chain_count() const;   ///< over all instances
    /// Skeleton nodes over all instances (produced or not: a joints-only simulation keeps only
    /// the chains' attach nodes, and reads no node positions; SimulationConfig::outputs).
    uint64_t node_count() const;
    uint64_t vertex_count() const;  ///< mesh vertices over all instances (produced or not)
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
