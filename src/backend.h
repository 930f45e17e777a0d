// The backend interface. A backend knows how to hold the buffers of gpu_layout.h and run one
// named pass over them; the pass sequence itself lives only in Simulation (simulation.cpp).
#pragma once

#include "buffers.h"
#include "pass_table.h"
#include "scene_data.h"

#include <hmsm/pass.h>
#include <hmsm/config.h>
#include <hmsm/status.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>

namespace hmsm::detail {

/// One dispatch of the step program: a pass over one instance group. The fields of `constants`
/// are final but `constants.wind_slot`, which the backend sets per step (see run()).
/// A CPU backend takes dt, max_angle and fix_weight from SceneData (double), a GPU backend from
/// the float copies in `constants`; every backend takes the wind from the wind table and
/// instance_wind buffers (gpu_layout.h), which the simulation writes.
struct Dispatch {
    Pass pass;
    gpu::PassConstants constants;
};

enum class Scalar { f32, f64 };

/// Elements [src, src + count) of a buffer go to [dst, dst + count) of the same buffer.
struct ElementMove {
    uint64_t src = 0, dst = 0, count = 0;
};

/// Elements [first, first + count) of a buffer: one of the ranges of read_ranges/write_ranges.
struct ElementRange {
    uint64_t first = 0, count = 0;
};

/// The bytes of the largest move in `moves` that changes anything (0: none does), after
/// `check_range(first, count)` accepted both ends of every move: what a device backend sizes
/// its scratch buffer by.
template <class CheckRange>
Result<uint64_t> largest_move_bytes(std::span<const ElementMove> moves, uint64_t element_bytes,
                                    CheckRange&& check_range) {
    uint64_t largest = 0;
    for (const ElementMove& m : moves) {
        HMSM_TRY(check_range(m.src, m.count));
        HMSM_TRY(check_range(m.dst, m.count));
        if (m.src != m.dst && m.count * element_bytes > largest) largest = m.count * element_bytes;
    }
    return largest;
}

/// How one step of a program with the walk that integrates ahead (is_walk_ahead, gpu_layout.h
/// HMSM_DISPATCH_WALK_AHEAD) runs. The step layer decides (step_program.h AheadSchedule, from
/// the simulation's change flags); a backend that walks ahead runs what it is told.
enum class AheadStep : uint8_t {
    /// The program as built: the wind pair integrates from chain_state, the walk ahead writes
    /// the next step's angles to chain_state's twin.
    whole,
    /// The angles the step before integrated ahead are this step's: the backend swaps the twin
    /// in and runs the program without its wind_force dispatches.
    take,
    /// The plain walk (AheadVariants::plain): no top poses, and no next angles written.
    plain,
};

/// One step of a run: the wind-table slot it reads (< HMSM_WIND_STEP_SLOTS, holding the step's
/// reduced wind clock, gpu_layout.h) and, in a program with the walk ahead, how it runs.
struct RunStep {
    uint32_t wind_slot = 0;
    AheadStep ahead = AheadStep::whole;
};

/// What a backend can do and prefers; the step layer (simulation.cpp, live_reshape.cpp,
/// step_program.cpp) builds its programs and chooses its paths from it.
struct BackendCapabilities {
    /// Instances may be added and removed in place: buffers keep their allocation and layout,
    /// state moves with move_elements and instance buffers are rewritten with write(). False (a
    /// Vulkan scene split into windows) makes the simulation upload the scene anew.
    bool reshapes_in_place = true;
    /// Each dispatch costs much more than a CUDA graph node (Vulkan: a pipeline barrier and its
    /// own command); the step program then runs pointer-jumping rounds in one dispatch for
    /// somewhat larger models (step_program.cpp rounds_in_dispatch_pay).
    bool dispatches_are_expensive = false;
    /// The backend can run path-walk step programs of forests that integrate ahead
    /// (gpu_layout.h HMSM_DISPATCH_WALK_AHEAD): it keeps chain_state's twin and runs each step
    /// as run()'s RunStep::ahead says (src/cuda/cuda_backend.cpp).
    bool walks_ahead = false;
    /// Composition::automatic resolves to path_walk here (measured fastest on GPUs) rather than
    /// pointer_jumping (the CPU backends, and Vulkan on a CPU driver).
    bool prefers_path_walk = false;
    /// The backend copies outputs to host memory of its own asynchronously (request_read and
    /// take_read below); otherwise the simulation reads them at the request.
    bool reads_async = false;
    /// copy_patterns() expands its patterns on the device: the host's work is in proportion to
    /// the copies and the patterns' moves, not to every move of every copy; level switches then
    /// copy kept chains straight from slot to slot (placed_layout.cpp). False: the default
    /// copy_patterns() through move_buffers(). HMSM_PATTERN_COPIES=0 turns it off on CUDA.
    bool copies_patterns = false;
    /// grow() below reallocates the capacity-sized buffers keeping their contents on the
    /// device; otherwise growth past the capacity uploads the scene anew (its state read back
    /// and written again).
    bool grows_on_device = false;
    /// The backend runs listed dispatches (gpu_layout.h PassConstants.instance_list: instances
    /// of one model wherever they lie, through the instance table); the simulation then lists a
    /// fragmented scene's instances per model (listed_groups.h).
    bool runs_listed_groups = false;
};

/// Read slots of request_read/take_read: one per Output, and one for Simulation::read().
inline constexpr uint32_t kReadSlots = 8;
inline constexpr uint32_t kSyncReadSlot = kReadSlots - 1;

/// The ranges of one buffer in read_buffers (`dst`) or write_buffers (`src`), their elements
/// back to back in host memory as in read_ranges/write_ranges.
struct BufferRangesRead {
    BufferId id{};
    std::span<const ElementRange> ranges;
    void* dst = nullptr;
};
struct BufferRangesWrite {
    BufferId id{};
    std::span<const ElementRange> ranges;
    const void* src = nullptr;
};
/// The moves of one buffer in move_buffers.
struct BufferMoves {
    BufferId id{};
    std::span<const ElementMove> moves;
};

/// Element moves relative to a source and a destination element, shared by the copies of one
/// copy_patterns call (a level switch's kept chains, the same for every tree that switches
/// between the same two levels).
struct MovePattern {
    std::span<const ElementMove> moves;
};
/// One copy of copy_patterns: each move m of the call's patterns[pattern] copies elements
/// [src + m.src, + m.count) to [dst + m.dst, + m.count).
struct PatternCopy {
    uint64_t src = 0, dst = 0;
    uint32_t pattern = 0;
};

/// Host bytes of one element of buffer `id` read or written as `as`.
inline uint64_t range_scalar_bytes(BufferId id, Scalar as) {
    return uint64_t(shape_scalars(buffer_info(id).shape)) * (as == Scalar::f64 ? 8 : 4);
}

class Backend {
public:
    virtual ~Backend() = default;

    virtual BackendKind kind() const = 0;
    /// Human-readable device, e.g. "NVIDIA H100 80GB HBM3" or "llvmpipe (LLVM 15.0.6, 256 bits)".
    virtual std::string device_name() const = 0;

    /// Allocates every buffer of kBufferTable sized by scene.element_count(), uploads the static
    /// buffers and zero-fills the others. Called once before anything below, and again when
    /// added instances outgrow the scene's capacities on a backend that cannot grow() or the
    /// backend cannot reshape in place (earlier buffers and their contents are released; the
    /// simulation writes the carried-over state back). Fails (never aborts) with out_of_memory
    /// or unsupported when the scene does not fit.
    virtual Status upload(const SceneData& scene) = 0;

    /// Only where capabilities().grows_on_device: reallocates the buffers sized by the
    /// capacities (capacity_growth.h sized_by_capacity: chain, node, vertex and instance scope)
    /// for `scene`'s capacities, each at least what upload() or the last grow() allocated, and
    /// copies their live elements (scene's live counts; both halves of a ping-pong buffer, the
    /// second of which moves to the new chain_capacity) from the old allocation on the device:
    /// nothing goes through the host. Elements past the live ones are zero; model-scope buffers
    /// and the wind table keep their allocation and contents. Fails with unsupported where the
    /// backend cannot grow this scene so (a Vulkan scene that would be split into windows) and
    /// with out_of_memory, in both cases with every buffer as it was.
    virtual Status grow(const SceneData& scene) {
        (void)scene;
        return {ErrorCode::unsupported, "this backend cannot grow its buffers on the device"};
    }

    /// Runs `program` steps.size() times, in order, one step each; step k runs every dispatch
    /// that reads the wind slot (reads_wind_slot) with constants.wind_slot = steps[k].wind_slot,
    /// and, in a program with the walk ahead, as steps[k].ahead says (only a backend whose
    /// capabilities().walks_ahead is true gets such programs). Dispatches see the writes of all
    /// earlier dispatches. Returns when all work is complete (CUDA under enqueue_steps: once it
    /// is enqueued on the backend's stream). A non-zero `program_id` names this exact program:
    /// the caller gives it to no other (the simulation numbers its step programs), so a backend
    /// that keeps what it derived from a program (plans, graphs, recordings) may recognize it by
    /// the id alone instead of comparing every dispatch; 0 names none (compare).
    virtual Status run(std::span<const Dispatch> program, std::span<const RunStep> steps,
                       uint64_t program_id = 0) = 0;

    /// Copies elements [first, first+count) of `id` (count * shape_scalars scalars; integer
    /// buffers are read as their numeric values) into `dst` as float or double.
    virtual Status read(BufferId id, uint64_t first, uint64_t count, void* dst, Scalar as) const = 0;
    /// The inverse of read(); for tests that set random states before running one pass.
    virtual Status write(BufferId id, uint64_t first, uint64_t count, const void* src,
                         Scalar as) = 0;

    /// read() of every range of `ranges`, in order, their elements back to back in `dst`. Ranges
    /// may overlap. A device backend copies them all with one round trip (a few where they
    /// exceed its staging memory); this default reads them one by one.
    virtual Status read_ranges(BufferId id, std::span<const ElementRange> ranges, void* dst, Scalar as) const {
        auto* out = static_cast<std::byte*>(dst);
        const uint64_t bytes = range_scalar_bytes(id, as);
        for (const ElementRange& r : ranges) {
            HMSM_TRY(read(id, r.first, r.count, out, as));
            out += r.count * bytes;
        }
        return {};
    }
    /// write() of every range of `ranges`, in order, their elements back to back in `src`; where
    /// ranges overlap the later one's values stay. A device backend copies them all at once; this
    /// default writes them one by one.
    virtual Status write_ranges(BufferId id, std::span<const ElementRange> ranges, const void* src, Scalar as) {
        const auto* in = static_cast<const std::byte*>(src);
        const uint64_t bytes = range_scalar_bytes(id, as);
        for (const ElementRange& r : ranges) {
            HMSM_TRY(write(id, r.first, r.count, in, as));
            in += r.count * bytes;
        }
        return {};
    }

    /// read_ranges of several buffers, with one round trip in all where the backend can (their
    /// bytes within its staging memory); this default reads buffer by buffer.
    virtual Status read_buffers(std::span<const BufferRangesRead> reads, Scalar as) const {
        for (const BufferRangesRead& r : reads) HMSM_TRY(read_ranges(r.id, r.ranges, r.dst, as));
        return {};
    }
    /// write_ranges of several buffers, in order; this default writes buffer by buffer.
    virtual Status write_buffers(std::span<const BufferRangesWrite> writes, Scalar as) {
        for (const BufferRangesWrite& w : writes) HMSM_TRY(write_ranges(w.id, w.ranges, w.src, as));
        return {};
    }
    /// move_elements of several buffers (each buffer's moves in order; buffers are apart), with
    /// one submission or wait in all where the backend can; this default moves buffer by buffer.
    virtual Status move_buffers(std::span<const BufferMoves> moves) {
        for (const BufferMoves& m : moves) HMSM_TRY(move_elements(m.id, m.moves));
        return {};
    }

    /// In every buffer of `ids` (chain scope; a ping-pong buffer's second half, from element
    /// `capacity` on, alike), every copy of `copies` (PatternCopy). No copy may write an
    /// element that another copy reads or writes, so order does not matter; nothing goes
    /// through the host. A pattern index past `patterns` is an internal error. This default
    /// expands every copy into move_buffers().
    virtual Status copy_patterns(std::span<const BufferId> ids, uint64_t capacity,
                                 std::span<const MovePattern> patterns, std::span<const PatternCopy> copies);
    /// Moves element ranges of buffer `id` on the device, in order, each as if through a
    /// temporary (source and destination may overlap): the state of instances that change place
    /// (live_reshape.cpp, lod_switch.cpp). Nothing goes through the host. A device backend
    /// copies a call's moves with a few copies or kernels whatever their number
    /// (element_moves.h plan_move_batches).
    virtual Status move_elements(BufferId id, std::span<const ElementMove> moves) = 0;
    /// Bracket a change of the instance list (live_reshape.cpp). A backend may hold back the
    /// writes, moves and runs made in between and carry them, in order, with the next work it
    /// does (Vulkan: in the next command buffer recorded by record_steps, docs/vulkan.md); any
    /// other call sees them done.
    virtual void begin_instance_change() {}
    virtual void end_instance_change() {}
    /// Whether the instance changes bracketed so are held back for an engine's frames (Vulkan,
    /// after a first record_steps): a read would then wait for frames the engine has in flight,
    /// so level requests do without one (lod_fade.cpp: a coarsening always fades).
    virtual bool holds_back_instance_changes() const { return false; }
    /// What the backend can do and prefers (BackendCapabilities); may change with upload()
    /// (Vulkan: whether the scene is split into windows).
    virtual BackendCapabilities capabilities() const { return {}; }

    /// Turns per-pass device timing on or off (off: pass_times() returns zeros).
    virtual void set_profiling(bool enabled) = 0;
    /// Device seconds per pass summed over the steps of the last run().
    virtual PassTimes pass_times() const = 0;

    /// Only where capabilities().reads_async: starts copying elements [first, first + count) of
    /// the float buffer `id`, as the work submitted so far leaves them, into host memory the
    /// backend owns for `slot` (< kReadSlots), replacing what the slot held, and returns
    /// without waiting for the copy. Calls on one slot are not concurrent.
    virtual Status request_read(uint32_t slot, BufferId id, uint64_t first, uint64_t count) const {
        (void)slot, (void)id, (void)first, (void)count;
        return {ErrorCode::internal, "this backend has no asynchronous read"};
    }
    /// Waits for the copy request_read started on `slot` and returns its elements as the
    /// buffer's float words (shape_scalars floats each); valid until the slot's next request.
    virtual Result<const float*> take_read(uint32_t slot) const {
        (void)slot;
        return Status{ErrorCode::internal, "this backend has no asynchronous read"};
    }

    /// Optional, for `hmsm bench`'s roofline: copies `bytes` between two device scratch
    /// buffers (allocated and freed here) a few times and returns the median device copy
    /// bandwidth, counted as (bytes read + bytes written) / device seconds. Default: unsupported.
    virtual Result<double> measure_copy_bandwidth(uint64_t bytes) {
        (void)bytes;
        return Status{ErrorCode::unsupported, "this backend cannot measure device copy bandwidth"};
    }
};

/// Backend factories; the registry (backend_registry.cpp) knows which are compiled in.
/// A factory returns no_device when it is compiled in but finds no usable device.
Result<std::unique_ptr<Backend>> create_cpu_backend(bool double_precision);
/// The most threads cpu-parallel takes (SimulationConfig::cpu_threads, HMSM_CPU_THREADS).
inline constexpr uint32_t kMaxCpuThreads = 1024;
/// Threads for cpu-parallel: `requested` when > 0, else the environment variable
/// HMSM_CPU_THREADS when set (invalid_argument unless an integer in [1, kMaxCpuThreads]), else
/// the hardware threads of the host.
Result<uint32_t> cpu_thread_count(uint32_t requested);
/// Cost units (about one chain of one compose round each, src/cpu/step_plan.h) below which a
/// dispatch of cpu-parallel is not split further: a chunk of a few microseconds, long against
/// the wait on another thread's chunk (a cache line passed between cores).
inline constexpr uint32_t kCpuMinChunkElements = 256;
/// cpu-parallel: the float passes of create_cpu_backend(false) over `threads` threads (0:
/// cpu_thread_count(0)); tests pass a small `min_chunk_elements` to split even tiny dispatches.
Result<std::unique_ptr<Backend>> create_cpu_parallel_backend(uint32_t threads,
                                                             uint32_t min_chunk_elements = kCpuMinChunkElements);
#ifdef HMSM_HAVE_VULKAN
Result<std::unique_ptr<Backend>> create_vulkan_backend();
#endif
#ifdef HMSM_HAVE_CUDA
Result<std::unique_ptr<Backend>> create_cuda_backend();
#endif

/// Creates the backend `kind`; `automatic` tries CUDA, then a Vulkan GPU, then cpu-parallel
/// where the host has more than one hardware thread (cpu_thread_count(cpu_threads) > 1), else
/// the serial CPU (float). `cpu_threads` is SimulationConfig::cpu_threads (0: default).
Result<std::unique_ptr<Backend>> create_backend(BackendKind kind, uint32_t cpu_threads = 0);

/// Buffers each pass reads and writes (bit i = BufferId i), for barrier placement.
uint32_t pass_reads(Pass pass);
uint32_t pass_writes(Pass pass);

/// What `d` runs (gpu_layout.h HMSM_DISPATCH_*; the step program sets only kinds that fit the
/// dispatch's pass, pass_table.h kind_fits_pass).
inline DispatchKind dispatch_kind(const Dispatch& d) { return DispatchKind(d.constants.kind); }
/// Whether `d` is a path-walk dispatch of Composition::path_walk: it also runs its pass's walk
/// partner (pass_table.h runs_walk_pair).
inline bool runs_path_walk(const Dispatch& d) { return runs_walk_pair(dispatch_kind(d)); }
/// The two dispatches of the walk that integrates ahead (gpu_layout.h).
inline bool is_top_poses_walk(const Dispatch& d) { return dispatch_kind(d) == DispatchKind::walk_top_poses; }
inline bool is_walk_ahead(const Dispatch& d) { return dispatch_kind(d) == DispatchKind::walk_ahead; }
/// Whether a dispatch reads the step's wind-table slot from constants.wind_slot (Backend::run
/// sets it): wind_force, integrate (the fades' clock, gpu_layout.h HMSM_FADE_*), the top poses
/// (which read the next step's, the slot after) and the walk ahead (which evaluates the
/// atmospheric wind and the fades of the slot after itself).
inline bool reads_wind_slot(const Dispatch& d) {
    return d.pass == Pass::wind_force || d.pass == Pass::integrate || is_top_poses_walk(d) || is_walk_ahead(d);
}
/// The passes a dispatch runs (bit i = Pass i): a path walk's two, or its own.
inline uint32_t dispatch_passes(const Dispatch& d) {
    if (runs_path_walk(d)) return walk_passes(d.pass);
    return 1u << uint32_t(d.pass);
}
/// Buffers a dispatch reads and writes (pass_table.h): a path walk's own columns, else the union
/// over the passes it runs.
/// A dispatch of the coupled dynamics adds pass_table.h's kCoupled* accesses.
inline bool runs_coupled(const Dispatch& d) { return d.constants.dynamics == HMSM_PASS_DYNAMICS_COUPLED; }
/// A dispatch of the articulated exchange adds pass_table.h's kArticulated* accesses.
inline bool runs_articulated(const Dispatch& d) { return d.constants.dynamics == HMSM_PASS_DYNAMICS_ARTICULATED; }
inline uint32_t dispatch_reads(const Dispatch& d) {
    if (is_top_poses_walk(d)) return kWalkTopPosesReads;
    if (is_walk_ahead(d)) return kWalkAheadReads;
    uint32_t reads = runs_path_walk(d) ? pass_info(d.pass).walk_reads : reads_of_passes(dispatch_passes(d));
    const uint32_t passes = dispatch_passes(d);
    if (runs_coupled(d) && (passes >> uint32_t(Pass::wind_force) & 1u)) reads |= kCoupledWindForceReads;
    if (runs_coupled(d) && (passes >> uint32_t(Pass::integrate) & 1u)) reads |= kCoupledIntegrateReads;
    if (runs_articulated(d) && (passes >> uint32_t(Pass::wind_force) & 1u)) reads |= kArticulatedWindForceReads;
    if (runs_articulated(d) && (passes >> uint32_t(Pass::integrate) & 1u)) reads |= kArticulatedIntegrateReads;
    return reads;
}
inline uint32_t dispatch_writes(const Dispatch& d) {
    if (is_top_poses_walk(d)) return kWalkTopPosesWrites;
    if (is_walk_ahead(d)) return kWalkAheadWrites;
    uint32_t writes = runs_path_walk(d) ? pass_info(d.pass).walk_writes : writes_of_passes(dispatch_passes(d));
    if (runs_coupled(d) && (dispatch_passes(d) >> uint32_t(Pass::wind_force) & 1u)) writes |= kCoupledWindForceWrites;
    if (runs_articulated(d) && (dispatch_passes(d) >> uint32_t(Pass::wind_force) & 1u))
        writes |= kArticulatedWindForceWrites;
    if (runs_articulated(d) && (dispatch_passes(d) >> uint32_t(Pass::integrate) & 1u))
        writes |= kArticulatedIntegrateWrites;
    return writes;
}
/// Whether a dispatch reads other chains' state anywhere in its instances though its pass is
/// not hierarchical: coupled wind_force's gather of the loads of the last step (its chunks are
/// planned by instance).
/// The articulated exchange (docs/model.md 3.13): integrate's work items are instances, each
/// sweeping its chains up and down the hierarchy (gpu_layout.h INSTANCE_SWEEP).
inline bool sweeps_instances(const Dispatch& d) { return dispatch_kind(d) == DispatchKind::instance_sweep; }
inline bool reads_across_chains(const Dispatch& d) {
    return (runs_coupled(d) && d.pass == Pass::wind_force) || sweeps_instances(d);
}

/// Number of threads of a dispatch and the mapping shared by every backend.
inline uint32_t dispatch_thread_count(const Dispatch& d) { return d.constants.element_count; }
/// Threads per instance of the group (element_count / instances): the model's chains, nodes or
/// vertices by the pass's domain, or the chains of one level (LEVEL) or of the top two levels
/// (WALK_TOP_POSES).
inline uint32_t threads_per_instance(const Dispatch& d) {
    const gpu::PassConstants& c = d.constants;
    switch (dispatch_kind(d)) {
        case DispatchKind::level:
        case DispatchKind::walk_top_poses: return c.level_count;
        default: break;
    }
    const uint32_t per_domain[] = {c.model_chain_count, c.model_node_count, c.model_vertex_count};
    return per_domain[uint32_t(pass_domain(d.pass))];
}

/// How a dispatch is launched: `workgroups` groups of `workgroup_size` threads. Every kind
/// maps thread i to element i (gpu_layout.h) except JUMP_ROUNDS_IN_DISPATCH, whose workgroup k
/// runs every round for group instance k, INSTANCE_SWEEP, whose workgroup k sweeps group
/// instance k, and CONTOUR_PACKED, whose thread places one model
/// vertex in HMSM_PACKED_CONTOUR_INSTANCES instances.
struct LaunchShape {
    uint64_t workgroups = 0;
    uint32_t workgroup_size = HMSM_WORKGROUP_SIZE;
};
inline bool runs_rounds_in_dispatch(const Dispatch& d) {
    return dispatch_kind(d) == DispatchKind::jump_rounds_in_dispatch;
}
inline bool runs_packed_contour(const Dispatch& d) { return dispatch_kind(d) == DispatchKind::contour_packed; }
inline LaunchShape launch_shape(const Dispatch& d) {
    const uint32_t threads = dispatch_thread_count(d);
    if (threads == 0) return {};
    if (runs_rounds_in_dispatch(d))
        return {threads / d.constants.model_chain_count, gpu::rounds_workgroup_size(d.constants.model_chain_count)};
    if (sweeps_instances(d)) {
        const uint32_t instances = threads / d.constants.model_chain_count;
        return {instances, gpu::sweep_workgroup_size(instances, d.constants.model_chain_count)};
    }
    const uint64_t launched = runs_packed_contour(d) ? gpu::packed_contour_threads(d.constants) : threads;
    return {(launched + HMSM_WORKGROUP_SIZE - 1) / HMSM_WORKGROUP_SIZE, HMSM_WORKGROUP_SIZE};
}

}  // namespace hmsm::detail
