// The state behind hmsm::Simulation (pimpl): everything a step needs, kept out of the public
// header so that adding a member changes no installed layout.
#pragma once

#include <hmsm/simulation.h>

#include "backend.h"
#include "cpu/thread_pool.h"
#include "instance_moves.h"
#include "instance_offsets.h"
#include "instance_placements.h"
#include "level_carry.h"
#include "level_staging.h"
#include "listed_groups.h"
#include "placed_list.h"
#include "lod_tracker.h"
#include "live_wind.h"
#include "scene_data.h"
#include "step_program.h"

#include <algorithm>
#include <array>
#include <map>
#include <memory>
#include <mutex>
#include <thread>
#include <unordered_map>
#include <vector>

namespace hmsm::detail {
struct LevelStaging;
}

namespace hmsm {

// Hidden: a nested class of the exported Simulation would otherwise be exported from libhmsm.so.
struct __attribute__((visibility("hidden"))) Simulation::Impl {
    static Result<std::unique_ptr<Simulation>> create(const Scene& scene,
                                                      const SimulationConfig& config,
                                                      std::unique_ptr<detail::Backend> backend,
                                                      detail::JumpingForm jumping_form = detail::JumpingForm::by_size);

    Status step(uint32_t count);
    /// Uploads what live control changed (wind table header, instance winds; live_control.cpp).
    /// The step program is rebuilt by current_program().
    Status apply_pending();
    /// The step program, rebuilt first if a change left it stale (live changes leave the
    /// rebuild to the next step, so a frame's changes rebuild it once).
    const std::vector<detail::Dispatch>& current_program();
    /// Writes the instance table of a listed step program (current_program) once it changed.
    Status write_instance_table();
    /// The step program over `groups` from pass `first` on (only the passes in `passes`, a bit
    /// per Pass).
    std::vector<detail::Dispatch> program_for(const std::vector<detail::InstanceGroup>& groups,
                                              Pass first, uint32_t passes = ~0u) const;
    /// Runs program_for(groups, first, passes) once at rest (a one-off program: posing added,
    /// reset or switched instances, outputs recomputed), listed where the groups are many and
    /// the backend can (listed_groups.h): the switched trees of a fragmented world are many
    /// scattered slices. Its table takes the instance table's place, so a listed step program
    /// writes its own again before it runs.
    Status run_at_rest(const std::vector<detail::InstanceGroup>& groups, Pass first, uint32_t passes = ~0u);
    /// Whether a program over `groups` should run listed groups (listed_groups.h): the backend
    /// runs them, the scene fits the table's words and listing pays. Fills `into` when it says
    /// so (and may fill it when it does not).
    bool lists(const std::vector<detail::InstanceGroup>& groups, detail::ListedGroups& into) const;
    /// Replaces the instance list: survivors (old indices, in their new order) then `added`;
    /// carries the survivors' state over and poses the added instances at rest
    /// (live_reshape.cpp).
    /// With `reupload`, the scene is uploaded anew even within the capacity (reserve_instances).
    Status reshape(const std::vector<uint32_t>& survivors, std::span<const Instance> added, bool reupload = false);
    /// reshape() within the capacity: moves state on the device, writes the added instances.
    Status reshape_in_place(std::unique_ptr<detail::SceneData> next, const std::vector<uint32_t>& survivors,
                            const std::vector<uint64_t>& old_chain, uint32_t first_moved);
    /// reshape() past the capacity: reads the state back, uploads `next` with room to grow,
    /// writes the state back.
    Status reshape_anew(std::unique_ptr<detail::SceneData> next, const std::vector<uint32_t>& survivors,
                        const std::vector<uint64_t>& old_chain);
    /// Checks that `instances` fit the 32-bit element counts of the device layout.
    Status check_size(std::span<const Instance> instances) const;
    /// check_size for `count` instances holding `elements` in the layout (O(1)).
    Status check_size(uint64_t count, const detail::ElementCounts& elements) const;

    // Streaming (live_stream.cpp): appends and swap removals within the capacity, at a cost in
    // proportion to the instances they touch (docs/driving.md, streaming budgets).
    /// Appends `added` (validated) in place; false when they do not fit the capacity.
    Result<bool> append_in_place(std::span<const Instance> added);
    /// Swap-removes `removed` (ascending, each once, fewer than all) in place; false when the
    /// staging of the instances that fill the holes does not fit the capacity (growth_ then
    /// says how much room the next upload takes).
    Result<bool> swap_remove_in_place(const std::vector<uint32_t>& removed);
    /// The host's lists after a swap removal, in either layout: each hole takes its filler's
    /// instance, handle, origin, yaw and LOD key, the lists are cut to the survivors; then the
    /// holes' origins, yaws and winds are written and the pending changes applied. The caller
    /// has carried the layout's own part (offsets or slots) first.
    Status swap_instance_lists(const std::vector<uint32_t>& removed, const detail::SwapFill& fill);
    /// Passes 4, 6 and 7 over every instance from the carried pose (every output buffer new or
    /// moved): element for element the outputs they had.
    Status recompute_outputs();
    /// Grows the capacities to hold `needed` elements and `instances` instances (1.5 times at a
    /// time, at least the reserve) on the device (Backend::grow, capacity_growth.cpp): true when
    /// they hold them now, false where the backend cannot grow so (the caller then takes the
    /// path that uploads the scene anew); an error (nothing changed) where the device has no
    /// memory for it.
    Result<bool> grow_on_device(const detail::ElementCounts& needed, uint64_t instances);
    /// Whether growth may take grow_on_device (HMSM_DEVICE_GROWTH=0 at create turns it off, for
    /// A/B measurements; tests compare both).
    bool device_growth_ = true;
    /// The first elements of the instances, rebuilt when a change laid the list out anew.
    detail::InstanceOffsets& offsets();
    /// Marks what the general paths (reshape, a switch past the capacity) leave stale: the
    /// offsets, the level tracker, the paused count.
    void instance_list_laid_out();
    detail::InstanceOffsets offsets_;
    bool offsets_valid_ = false;

    // The placed layout (SimulationConfig::instance_layout, instance_placements.h;
    // placed_layout.cpp): in force while placed_, set at create where the backend runs listed
    // groups and reshapes in place. Every step program and one-off run then lists its
    // instances with their slots; the general paths (reshape, a switch past the capacity) pack
    // the layout first (pack_layout) and lay it out anew, packed.
    bool placed_ = false;
    detail::InstancePlacements placements_;
    /// The step program's instance table in the placed layout, kept under changes.
    detail::PlacedList placed_list_;
    /// Whether the placed layout can be in force: the config asks for it, the backend runs
    /// listed groups and reshapes in place, the scene fits the table's words.
    bool wants_placed() const;
    /// The layout was laid out packed (create, the general paths): the slots, the table anew.
    void placements_laid_out();
    /// run_at_rest over the instances `indices` (ascending, each once) at their slots.
    Status run_at_rest_placed(std::span<const uint32_t> indices, Pass first, uint32_t passes = ~0u);
    /// Puts the chains `ranges` at rest: S = V = 0, g = 0 and both halves of the loads and of the
    /// articulated exchange's impulses (T, R, O are computed from them by a run from pass 2),
    /// every range in one write per buffer.
    Status zero_chain_state(std::span<const detail::ElementRange> ranges);
    /// Runs one_off_listed_'s program at rest; in the placed layout its table goes behind the
    /// step program's where the instance table has room for both.
    Status run_one_off(Pass first, uint32_t passes);
    /// Instance i's first chain, node and vertex in the layout in force.
    detail::ElementCounts first_elements(uint32_t i);
    /// Copies the placed layout's end into the scene (SceneData::placed_*_end), which growth
    /// and reads cover.
    void placed_end_changed();
    /// Moves every instance to its packed place (the state through the host, the outputs
    /// recomputed), so that a general path may take the layout as packed; nothing where it is.
    Status pack_layout();
    /// append_in_place, swap_remove_in_place and the part of switch_models within the capacity
    /// in the placed layout: each changed instance takes a slot, nothing else moves.
    Result<bool> append_placed(std::span<const Instance> added);
    Status swap_remove_placed(const std::vector<uint32_t>& removed);
    /// Builds the switched instances (`models`: index, new run model; their carries) in new
    /// slots, straight from their old slots where the backend copies patterns, otherwise
    /// through the staging above every slot held, and frees their old slots. False where the
    /// slots and the staging do not fit the capacity even after growing it.
    Result<bool> switch_placed(const std::vector<std::pair<uint32_t, uint32_t>>& models,
                               const std::vector<const detail::LevelCarry*>& carries);
    /// switch_placed's copies into the new `slots`: by pattern (Backend::copy_patterns, the
    /// staging holding the templates alone) or through the whole staging (move_buffers).
    Status copy_switched_chains(const std::vector<std::pair<uint32_t, uint32_t>>& models,
                                const std::vector<const detail::LevelCarry*>& carries,
                                const detail::LevelStaging& staging, const std::vector<detail::ElementCounts>& slots);
    Status move_switched_chains(const std::vector<std::pair<uint32_t, uint32_t>>& models,
                                const std::vector<const detail::LevelCarry*>& carries,
                                const detail::LevelStaging& staging, const std::vector<detail::ElementCounts>& slots);
    /// The templates of switch_placed's pattern copies (the slots ending at `slots_end`) from
    /// template_zone_, written first where they are not: false, and the zone forgotten, where
    /// the zone does not fit above the slots.
    Result<bool> staging_from_template_zone(uint64_t slots_end, const std::vector<std::pair<uint32_t, uint32_t>>& models,
                                            const std::vector<const detail::LevelCarry*>& carries,
                                            detail::LevelStaging& staging);
    detail::TemplateZone template_zone_;
    /// Paused instances (Instance::active false): none lets the step program take the groups
    /// as they are.
    uint64_t paused_count_ = 0;
    detail::LodTracker lod_tracker_;
    /// Whether add, swap removal and level switches take the streaming paths (tests compare
    /// them with the general ones: reshape, and a level switch laid out anew).
    bool streaming_paths_ = true;
    /// Checks the force of `fields` against the float range (docs/model.md 3.11).
    Status check_forces(std::span<const ForceField> fields) const;
    /// Checks the wind force of every chain of the instances under `wind`: O(models) while the
    /// largest instance load leaves room, instance by instance (naming the first offender)
    /// only near the limit.
    Status check_instance_forces(const Wind& wind) const;
    /// The largest wind_scale * A_c over the instances (cached until instances_changed()).
    double largest_instance_load() const;
    /// Every change of an instance's model or wind scale, and of the instance list, calls it.
    void instances_changed() { largest_instance_load_ = -1.0; }
    /// Resets `indices` to rest (S = V = 0, posed at rest); live_control.cpp.
    Status reset(std::span<const uint32_t> indices);
    /// Checks that `wind` keeps every force and phase of the instances finite. With
    /// `in_force`, the wind the instances were checked against so far, phases that depend on
    /// nothing that changed are not checked again (an engine's gust each frame stays O(models)).
    Status check_wind(const Wind& wind, const Wind* in_force = nullptr) const;
    /// Where an output comes from (simulation_read.cpp).
    struct ReadSource {
        Output output = Output::node_positions;
        detail::BufferId id = detail::BufferId::node_world;
        uint64_t count = 0;          // elements of the output
        uint64_t held = 0;           // elements read: the output's, or every slot's (placed)
        uint32_t stored = 4;         // scalars per stored element
        bool packed_normals = false;  // normals decoded from the positions' w words
        /// The placed layout: where each instance's elements lie among those read (src) and
        /// go in the output (dst), neighbours joined; empty where they are the output's order.
        std::vector<detail::ElementMove> gather;
    };
    /// `raw` (source.held stored elements) in the output's order: `raw` itself, or gathered
    /// into `into` by source.gather.
    template <class Stored>
    const Stored* gathered(const ReadSource& source, const Stored* raw, std::vector<Stored>& into) const;
    /// The source of `output`, or invalid_argument (message starting with `fn`) when the
    /// simulation does not produce it.
    Result<ReadSource> read_source(Output output, const char* fn) const;
    /// The output's values from its stored elements `raw`, into `out`: large outputs in
    /// chunks on the readback threads, each element converted as a single pass would.
    template <class Stored, class Out>
    void unpack(const ReadSource& source, const Stored* raw, std::vector<Out>& out) const;
    /// Calls body(begin, end) over disjoint element ranges covering [0, count): one range
    /// when the output is small, else ranges of about a MiB spread over the readback threads.
    template <class F>
    void for_element_ranges(uint64_t count, uint64_t bytes_per_element, F&& body) const {
        constexpr uint64_t kRangeBytes = uint64_t(1) << 20;  // amortizes waking a thread
        in_ranges(count, std::max<uint64_t>(1, kRangeBytes / std::max<uint64_t>(1, bytes_per_element)),
                  std::forward<F>(body));
    }
    /// Calls body(begin, end) over disjoint ranges covering [0, count), each of about
    /// `per_range` items (one range where count is below two of them), spread over the
    /// readback threads (at most eight: they saturate the memory bus); the split depends on
    /// count and per_range only. `body` must not throw; the ranges must be independent.
    template <class F>
    void in_ranges(uint64_t count, uint64_t per_range, F&& body) const {
        constexpr uint32_t kMostThreads = 8;
        const uint64_t ranges = std::min<uint64_t>(count / std::max<uint64_t>(1, per_range), 64 * kMostThreads);
        const uint32_t threads = std::min(kMostThreads, std::max(1u, std::thread::hardware_concurrency()));
        if (ranges < 2 || threads < 2) {
            if (count > 0) body(uint64_t(0), count);
            return;
        }
        std::lock_guard lock(unpack_mutex_);
        if (!unpack_pool_) unpack_pool_ = std::make_unique<detail::cpu::ThreadPool>(threads);
        unpack_pool_->for_each(uint32_t(ranges), [&](uint32_t k) {
            const uint64_t begin = k * count / ranges, end = (k + 1) * count / ranges;
            if (begin < end) body(begin, end);
        });
    }
    template <class Out>
    Status read_into(Output output, std::vector<Out>& out) const;
    Status request_read(Output output);
    template <class Out>
    Status take_read(Output output, std::vector<Out>& out);

    /// Levels of detail at run time (lod_switch.cpp): builds the levels of scene model `m`
    /// (Scene::lod_budgets) from its full hierarchy and mesh, kept until append_lod_levels().
    Status add_lod_levels(uint32_t m, const Hierarchy& full, const MeshTemplate& full_mesh);
    /// Appends the levels built by add_lod_levels() as models after the scene's.
    Status append_lod_levels();
    /// Runs every instance of `models` (current index -> new model) on its new model, keeping
    /// its index and carrying the state of the chains both models keep (lod_switch.cpp).
    Status switch_models(const std::vector<std::pair<uint32_t, uint32_t>>& models);
    /// How a switch from run model `from` to `into` carries the chains (made on first use).
    const detail::LevelCarry& level_carry(uint32_t from, uint32_t into);
    std::unordered_map<uint64_t, detail::LevelCarry> level_carries_;  // by from << 32 | into

    /// A model the simulation runs: a scene model (level 0, as Scene::joint_budgets runs it) or
    /// one of its levels of detail. source_chain maps its chains to the full model's.
    struct LodModel {
        uint32_t scene_model = 0;
        uint32_t level = 0;
        std::vector<int32_t> source_chain;
    };
    /// Per run model: scene models first (index = scene model), then their levels.
    std::vector<LodModel> lod_models_;
    /// Per scene model: the run model of each level (level 0: the scene model itself).
    std::vector<std::vector<uint32_t>> levels_of_;
    /// Levels built by add_lod_levels() during create(), appended by append_lod_levels().
    struct PendingLevel {
        Hierarchy hierarchy;
        MeshTemplate mesh;
        LodModel lod;
    };
    std::vector<PendingLevel> pending_levels_;
    LodBands lod_bands_;

    /// Fades to coarser levels (lod_fade.cpp, docs/model.md 3.12): per fading instance's
    /// handle, the run model it fades from and to, the number of the fade's last step (while the
    /// instance is active) and the steps it has left (kept aside while it is paused).
    struct LodFade {
        uint32_t from_model = 0, target_model = 0;
        uint64_t end_step = 0;
        uint32_t paused_left = 0;
    };
    std::unordered_map<uint64_t, LodFade> fades_;
    /// The fades by the step their instance may end them at (end_step while active; the step
    /// it was paused at with no steps left), id by id: ended_fades looks at the fades whose
    /// step came, not at every fade. Entries outlive their fade or its end (they are checked
    /// against fades_ when their step comes); every change of a fade's end adds one. Ids by
    /// step: the fades of a step share one entry of the map (about fade_steps of them).
    std::map<uint64_t, std::vector<uint64_t>> fade_ends_;
    /// Adds fade_ends_'s entry of the fade of `id`, now ending at `step`.
    void fade_ends_at(uint64_t id, uint64_t step) { fade_ends_[step].push_back(id); }
    /// Per run model: its rank among its scene model's levels by chain count, finest first (the
    /// fade word's level, gpu_layout.h HMSM_FADE_*).
    std::vector<uint32_t> fold_rank_;
    /// Fills fold_rank_ and returns, per model chain of every run model in order, the rank of
    /// the coarsest level that keeps the chain (SceneData::chain_keep_level); refuses a model
    /// with more than HMSM_MAX_LOD_LEVELS levels.
    Result<std::vector<uint32_t>> chain_keep_ranks();
    /// The fade word of instance `index` (0: it does not fade), for instance_wind.
    double fade_word(uint32_t index) const;
    /// fades_'s entry of instance `index`, or fades_.end(): looked up only where the LOD
    /// tracker does not know that the instance has none.
    std::unordered_map<uint64_t, LodFade>::iterator fade_of(uint32_t index) {
        if (fades_.empty() || (lod_tracker_.valid && lod_tracker_.may_fade[index] == 0)) return fades_.end();
        return fades_.find(uint64_t(instance_ids_[index]));
    }
    /// Keeps the steps left of instance `index`'s fade while it is paused (`active` false) and
    /// counts them on from the current step when it resumes.
    void pause_fade(uint32_t index, bool active);
    /// Per mark of `fading` (index, target run model; ascending indices): whether the instance
    /// is at rest, its deflection bound D within LodBands::fade_bound_m (read through the host);
    /// none where fade_bound_m is 0 or the backend holds instance changes back (nothing read).
    Result<std::vector<uint8_t>> fades_at_rest(const std::vector<std::pair<uint32_t, uint32_t>>& fading);
    /// Per run model, per chain: e_c, the largest rest distance from the chain's attach node
    /// to a node or mesh vertex of its subtree (filled on first use).
    mutable std::vector<std::vector<double>> subtree_extent_;
    /// Levels asked for (current index, level), in any order: finer or equal levels switch at
    /// once, coarser ones fade by lod_bands_. `ended` (ended_fades) switch to their targets in
    /// the same switch where no request names them, else first. Returns how many instances
    /// changed level or target.
    Result<uint64_t> request_lods(std::vector<std::pair<uint32_t, uint32_t>> requests,
                                  std::vector<std::pair<uint32_t, uint32_t>> ended = {});
    /// The fades that are over (all their steps run) as (index, target model), ascending; they
    /// stay in fades_ (an instance heads for its target) until request_lods switches them. Drops
    /// the fades whose instance was switched another way (their fade words are rewritten).
    /// O(fades whose end came, log fades); removals drop their instances' fades themselves.
    std::vector<std::pair<uint32_t, uint32_t>> ended_fades();
    /// Switches the ended fades (ended_fades) at once.
    Status fold_ready_fades();
    /// step() while fades run: folds the fades that are over, then runs the steps in one go
    /// (chunks of at most kStepsBetweenFolds, lod_fade.cpp).
    Status step_fading(uint32_t count);
    const std::vector<double>& subtree_extent(uint32_t model) const;
    /// The current index of instance `id`, or -1 if it is not live.
    int64_t live_index(uint64_t id) const;

    SimulationConfig config_;
    /// The dispatch form of Composition::pointer_jumping (by size unless a test or the bench
    /// forces one through Simulation::Access).
    detail::JumpingForm jumping_form_ = detail::JumpingForm::by_size;
    Scene scene_;
    std::vector<Hierarchy> hierarchies_;
    std::vector<MeshTemplate> meshes_;
    std::vector<double> largest_wind_area_;  // per model: the largest chain wind area A_c
    mutable double largest_instance_load_ = -1.0;  // largest_instance_load(); < 0: not known
    std::unique_ptr<detail::SceneData> data_;
    std::unique_ptr<detail::Backend> backend_;
    std::vector<detail::Dispatch> step_program_;
    /// Numbers step_program_'s contents: a rebuild takes the next id (Backend::run program_id).
    uint64_t step_program_id_ = 0;
    bool step_program_walks_ahead_ = false;  // whether step_program_ has the walk ahead
    /// The listed groups of step_program_ where it lists (listed_groups.h), and whether their
    /// instance table still has to be written to the backend before the program runs.
    detail::ListedGroups listed_;
    bool instance_table_dirty_ = false;
    bool step_program_lists_ = false;     // step_program_ runs listed_'s groups
    detail::ListedGroups one_off_listed_;  // run_at_rest's scratch
    std::vector<ForceField> force_fields_;
    std::vector<Instance> instances_;  // the current instance list (live control)
    /// The handle of each current instance: survivors keep their order and added instances
    /// take next_instance_id_ on, so the ids stay ascending until a swap removal moves one.
    std::vector<InstanceId> instance_ids_;
    /// Whether instance_ids_ is ascending (index_of searches it); otherwise index_of uses
    /// id_index_, the index of each current id (kept by the streaming paths, rebuilt by reshape).
    bool ids_ascending_ = true;
    std::unordered_map<uint64_t, uint32_t> id_index_;
    uint64_t next_instance_id_ = 0;
    /// The room reserve_instances() asked for: a re-upload allocates at least this much.
    struct Reserved {
        uint64_t chains = 0, nodes = 0, vertices = 0, instances = 0;
    };
    Reserved reserved_;
    /// Keeps `room` as the reserve and grows the capacities to it now if they are smaller (on
    /// the device, or by uploading the scene anew); nothing changes on an error
    /// (capacity_reserve.cpp).
    Status reserve_room(const Reserved& room);
    /// Room the next upload takes at least (a swap removal's staging asked for it); cleared by it.
    Reserved growth_;
    detail::WindClock clock_;
    detail::WindModes modes_{};
    bool program_dirty_ = true, header_dirty_ = true, instance_wind_dirty_ = true;
    std::vector<uint32_t> dirty_instances_;  // instance_wind elements to rewrite
    std::vector<detail::RunStep> run_steps_;  // scratch: the wind-table slot of each step of a run
    /// The walk that integrates ahead: whether a run's steps may take the angles integrated
    /// ahead (live control calls live_change()).
    detail::AheadSchedule ahead_schedule_;
    std::vector<double> wind_scratch_;
    // Scratch for read(): elements as the backend stores them, kept between calls so a
    // per-frame readback neither allocates nor zero-fills.
    mutable std::vector<float> stored_f32_, gathered_f32_;
    mutable std::vector<double> stored_f64_, gathered_f64_;
    // Serializes read(): the scratch above and the backends' readback paths (a staging buffer
    // and a queue submission on Vulkan, pinned memory on CUDA) are shared, and const calls may
    // run concurrently (the threading contract in include/hmsm/simulation.h).
    mutable std::mutex read_mutex_;
    // The threads that convert large readbacks and examine many instances in update_lod
    // (in_ranges; started on first use), and the lock that keeps read(), take_read() and
    // update_lod from sharing them at once.
    mutable std::unique_ptr<detail::cpu::ThreadPool> unpack_pool_;
    mutable std::mutex unpack_mutex_;
    /// request_read's requests, one per Output: what was requested and, where the backend does
    /// not read asynchronously, the elements read at the request.
    struct PendingRead {
        bool requested = false;
        ReadSource source;
        std::vector<float> f32;
        std::vector<double> f64;
    };
    std::array<PendingRead, detail::kSyncReadSlot> pending_reads_;
    PassTimes times_;  // over the chunks of the last step() call
    uint64_t steps_done_ = 0;
    /// Times add/remove re-uploaded the whole scene (capacity outgrown, or a backend that
    /// cannot reshape in place); tests check that in-place changes leave it alone.
    uint64_t full_uploads_ = 0;
    /// Times growth past the capacity took grow_on_device instead.
    uint64_t device_growths_ = 0;
    /// Reads of fading instances' state by fades_at_rest (a test hook: fade_bound_m 0 and an
    /// engine's recording read none).
    uint64_t at_rest_reads_ = 0;
};

}  // namespace hmsm
