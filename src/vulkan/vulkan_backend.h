// The Vulkan backend: the scene's buffers in device-local memory, the seven pipelines, and
// run() recording the step program into command buffers (chunks of steps, two in flight so the
// host records the next chunk while the device runs the previous one), with per-dispatch
// timestamps summed into PassTimes when profiling is on. Scenes whose state buffers exceed
// maxStorageBufferRange are bound in windows, one descriptor set per segment of instances, and
// each dispatch is recorded as one part per segment (windows.h). Steps recorded into an engine's
// command buffer take their live changes from a ring of frame slots (frame_ring.h) and replay
// the program's commands built once (recorder.h RecordingPlan), recorded once into secondary
// command buffers and replayed (step_replay.h): no submission, no wait. Each
// run of dispatches of one pass over many instance groups is one launch whose workgroups find
// their constants in the run table (run_table.h), on a GPU (HMSM_VULKAN_BATCH_RUNS=0 or 1
// decides).
#pragma once

#include "device.h"
#include "fault_injection.h"
#include "device_buffer.h"
#include "frame_ring.h"
#include "pipelines.h"
#include "range_copy.h"
#include "recorder.h"
#include "run_table.h"
#include "read_slots.h"
#include "step_replay.h"
#include "windows.h"

#include "../backend.h"
#include "../element_moves.h"

#include <array>
#include <functional>
#include <memory>

namespace hmsm::detail::vk {

/// Whether blocking steps hold instance changes back until the next submission (the default;
/// HMSM_VULKAN_HOLD_BACK=0 submits each as it is made).
bool blocking_hold_back_requested();

class VulkanBackend final : public Backend {
public:
    /// `frames_in_flight` (1 to kMaxFramesInFlight) sizes the ring of live parameters of
    /// recorded steps (frame_ring.h, hmsm::vulkan::ExternalContext::frames_in_flight).
    static Result<std::unique_ptr<VulkanBackend>> create(std::shared_ptr<Device> device,
                                                         uint32_t frames_in_flight = 3);
    ~VulkanBackend() override;

    BackendKind kind() const override { return BackendKind::vulkan; }
    std::string device_name() const override { return device_->name(); }
    Status upload(const SceneData& scene) override;
    /// New buffers for the capacity-sized ids and one submission of vkCmdCopyBuffer (the live
    /// elements) and vkCmdFillBuffer (the rest), which waits; the descriptor sets are made
    /// anew. Held-back changes are submitted first. Only for a scene in one window that stays
    /// in one (growth.cpp); else unsupported, and the simulation uploads the scene anew.
    Status grow(const SceneData& scene) override;
    Status run(std::span<const Dispatch> program, std::span<const RunStep> steps, uint64_t program_id = 0) override;
    Status read(BufferId id, uint64_t first, uint64_t count, void* dst, Scalar as) const override;
    Status write(BufferId id, uint64_t first, uint64_t count, const void* src, Scalar as) override;
    /// The moves copy through a device-local scratch buffer (vkCmdCopyBuffer forbids
    /// overlapping regions), all in one submission: per batch of plan_move_batches one copy
    /// command gathers every source into scratch and one scatters them (element_moves.h).
    Status move_elements(BufferId id, std::span<const ElementMove> moves) override;
    /// One submission per staging-full of ranges, each one copy command with a region per range
    /// (a split scene's ping-pong buffers: range by range).
    Status read_ranges(BufferId id, std::span<const ElementRange> ranges, void* dst, Scalar as) const override;
    /// As read_ranges; held back or staged into a recording range by range, as write() is.
    Status write_ranges(BufferId id, std::span<const ElementRange> ranges, const void* src, Scalar as) override;
    /// Every buffer's ranges in one submission, within the staging buffer's size.
    Status read_buffers(std::span<const BufferRangesRead> reads, Scalar as) const override;
    Status write_buffers(std::span<const BufferRangesWrite> writes, Scalar as) override;
    /// Every buffer's moves in one submission (held back: buffer by buffer, as move_elements).
    Status move_buffers(std::span<const BufferMoves> moves) override;
    /// Through copy_patterns.comp (range_copy.h) in one submission; held back or recorded into
    /// an engine's command buffer, or where the range copies are off, the default.
    Status copy_patterns(std::span<const BufferId> ids, uint64_t capacity, std::span<const MovePattern> patterns,
                         std::span<const PatternCopy> copies) override;
    void set_profiling(bool enabled) override { profiling_ = enabled; }
    /// Once the simulation has recorded steps into an engine's command buffer, an instance
    /// change within the capacity holds its writes, moves and at-rest runs back for the next
    /// recording (deferred_changes.cpp): add_instances and remove_instances neither submit nor
    /// wait. Any other operation (step(), read(), upload, ...) submits them first.
    void begin_instance_change() override { in_instance_change_ = true; }
    void end_instance_change() override { in_instance_change_ = false; }
    bool holds_back_instance_changes() const override { return engine_recorded_; }
    /// Changes held back for the next recording (a test hook).
    size_t held_back_changes() const { return held_back_.size(); }
    PassTimes pass_times() const override { return times_; }

    // Engine interop (hmsm/vulkan.h).
    const Device& device() const { return *device_; }
    /// One VkBuffer per BufferId, whatever its size. Every buffer but chain_rotation and
    /// chain_origin is laid out as gpu_layout.h says; those two are segment-major in a split
    /// scene (windows.h).
    const Buffer& buffer(BufferId id) const { return buffers_[uint32_t(id)]; }
    uint64_t element_count(BufferId id) const { return element_counts_[uint32_t(id)]; }
    /// The scene's segments (one unless a buffer exceeds the window); valid after upload().
    const WindowPlan& window_plan() const { return *plan_; }
    /// Until end_recording(), run() records into `command_buffer` instead of submitting (and
    /// returns before the work executes), and write() stages its data in the next frame's slot
    /// of the ring and records the copy to the device ahead of the steps: nothing is submitted
    /// or waited for.
    /// Records the changes held back since the last recording first.
    Status begin_recording(VkCommandBuffer command_buffer);
    /// Records the copies of writes made after the last run() and restores normal submission.
    Status end_recording();
    uint32_t frames_in_flight() const { return ring_->frames(); }
    /// Queue submissions hmsm made itself on this backend (step, read, write outside a
    /// recording, ...); a test hook: record_steps makes none.
    uint64_t submissions() const { return submissions_ + transfer_->submissions() + read_slots_->submissions(); }
    /// Dispatches of the range copy (range_copy.h) so far (a test hook).
    uint64_t range_copy_dispatches() const { return range_copier_ ? range_copier_->dispatches() : 0; }
    /// Held-back moves recorded into engines' command buffers as copy commands rather than as a
    /// dispatch (a test hook: few moves, or moves that overlap their sources).
    uint64_t moves_recorded_as_copies() const { return moves_recorded_as_copies_; }
    /// Secondary command buffers recorded for recorded steps, and their vkCmdExecuteCommands
    /// (test hooks; step_replay.h): a frame loop whose program stays records none after the
    /// first frames in flight. Both 0 with replay off.
    uint64_t step_secondaries_recorded() const { return replay_ ? replay_->secondaries_recorded() : 0; }
    uint64_t step_replays() const { return replay_ ? replay_->replays() : 0; }
    /// Copy commands recorded into engines' command buffers (a test hook): a replayed frame's
    /// wind table travels in its secondary, so a steady frame loop records none.
    uint64_t engine_copy_commands() const { return ring_->copy_commands() + wind_copies_in_engine_buffers_; }
    /// vkCmdDispatch calls per step of the program last run (a test hook).
    size_t launches_per_step() const { return recording_.launches(); }
    /// Whether runs of dispatches are batched (vulkan_set_batch_runs, HMSM_VULKAN_BATCH_RUNS).
    bool batches_runs() const { return batching_.batch_runs; }

    /// One copy command per output into a host-visible buffer of the slot's (read_slots.h);
    /// an output past one allocation goes through the staging chunks.
    Status request_read(uint32_t slot, BufferId id, uint64_t first, uint64_t count) const override;
    Result<const float*> take_read(uint32_t slot) const override;
    /// For `hmsm bench`'s roofline (copy_bandwidth.cpp): the faster of vkCmdCopyBuffer and a
    /// compute-shader copy between two scratch device-local buffers, each the median of
    /// timestamped runs, as (bytes read + bytes written) / seconds.
    Result<double> measure_copy_bandwidth(uint64_t bytes) override;
    /// Dispatches are expensive; the path walk on a GPU, not on a CPU driver; reshaping in place
    /// but for a scene split into windows (its ping-pong buffers are segment-major).
    BackendCapabilities capabilities() const override {
        BackendCapabilities can;
        can.reshapes_in_place = plan_ && !plan_->split();
        can.dispatches_are_expensive = true;
        can.prefers_path_walk = !device_->is_cpu();
        can.grows_on_device = can.reshapes_in_place;
        // A listed dispatch reads state anywhere, so only within one window (windows.h).
        can.runs_listed_groups = can.reshapes_in_place;
        can.reads_async = true;
        can.copies_patterns = can.reshapes_in_place && range_copier_ && batch_transfers_ && pattern_copies_;
        return can;
    }

private:
    /// One command buffer in flight: its fence, timestamp pool and what it ran.
    struct Slot {
        VkCommandBuffer command_buffer = VK_NULL_HANDLE;
        VkFence fence = VK_NULL_HANDLE;
        VkQueryPool timestamps = VK_NULL_HANDLE;
        uint32_t timestamp_capacity = 0;
        bool in_flight = false;
        size_t steps = 0;  // steps recorded into the command buffer
        const RecordingPlan* plan = nullptr;  // the plan they were recorded from
    };

    explicit VulkanBackend(std::shared_ptr<Device> device);
    /// A lost device (injected) fails every later operation, as a real lost device does.
    Status check_device_lost() const;
    /// [first, first + count) lies inside buffer `id` (read/write).
    Status check_range(BufferId id, uint64_t first, uint64_t count) const;
    /// Static model buffers within maxStorageBufferRange; the segments of the state buffers.
    Status plan_windows(const SceneData& scene);
    Status upload_static(BufferId id, const SceneData& scene);
    /// How buffer `id` is used: storage and transfer, and vertex input for the shared outputs.
    static VkBufferUsageFlags usage_of(BufferId id);
    Status submit_chunk(Slot& slot, const RecordingPlan& plan, std::span<const RunStep> steps);
    /// Waits for `slot` and adds its timestamps to times_ (of its plan's timed parts).
    Status finish_slot(Slot& slot);
    /// The recording plan of `program`, and the run table's contents where the plan is new.
    Status prepare_recording(std::span<const Dispatch> program, uint64_t program_id);
    /// The plan of a one-off program (program_id 0: the pose of added, reset or switched
    /// instances), recorded without batching: it leaves the step program's plan, run table and
    /// replayed secondaries as they are, so a streaming frame records none of them again.
    Status prepare_one_off(std::span<const Dispatch> program);
    Status ensure_timestamp_capacity(Slot& slot, uint32_t queries);
    /// A write, move or run of an instance change held back for the next recording; `ranges`:
    /// one write_ranges call (its data packed), `patterns`: a pattern copy of buffers `ids`.
    struct HeldBack {
        enum class Kind { write, move, run, ranges, patterns } kind;
        BufferId id{};
        uint64_t first = 0, count = 0;
        Scalar as = Scalar::f32;
        std::vector<std::byte> data;
        std::vector<ElementMove> moves;
        std::vector<Dispatch> program;
        std::vector<RunStep> steps;
        std::vector<ElementRange> ranges;
        std::vector<BufferId> ids;
        std::vector<PatternRow> entries, rows;  // a pattern copy's entries and moves
    };
    /// Whether a write, move or run that stages `staged_bytes` is held back rather than done
    /// now: within an instance change, under an engine's recording always, and otherwise
    /// (blocking steps) while what is held stays within kBlockingHeldBytes.
    bool holding_back(uint64_t staged_bytes = 0) const {
        if (!in_instance_change_ || record_target_ || releasing_) return false;
        return engine_recorded_ ||
               (hold_back_blocking_ && held_back_bytes_ + staged_bytes <= kBlockingHeldBytes);
    }
    /// Queues a held-back change that stages `staged_bytes`.
    void hold_back(HeldBack change, uint64_t staged_bytes);
    /// Submits the held-back changes (before any operation that is not itself held back):
    /// outside an engine's recording recorded into one command buffer through the frame ring
    /// (one submission and one wait), else each as it would have run.
    Status submit_held_back();
    /// Records the held-back changes into the recording's command buffer, in order.
    Status record_held_back();
    Status hold_back_write(BufferId id, uint64_t first, uint64_t count, const void* src, Scalar as);
    /// Whether a write of `ranges` of buffer `id` that cannot be submitted now (held back, or
    /// inside a recording) goes as one scatter in the recording (range_copy.h, *_in_frame)
    /// rather than a ring copy per range.
    bool scatters_in_frame(BufferId id, std::span<const ElementRange> ranges) const;
    /// A write of `ranges` (`src` as `as`, packed) into the recording's command buffer: the
    /// scatter where scatters_in_frame, else a ring copy per range.
    Status record_ranges_in_frame(BufferId id, std::span<const ElementRange> ranges, const void* src, Scalar as);
    /// Pattern copies (copy_patterns' tables as PatternRows) of buffers `ids`, whose halves lie
    /// `capacity` elements apart: submitted now, or recorded into the recording's command buffer.
    Status patterns_now(std::span<const BufferId> ids, uint64_t capacity, std::span<const PatternRow> entries,
                        std::span<const PatternRow> moves);
    Status record_patterns_in_frame(std::span<const BufferId> ids, uint64_t capacity,
                                    std::span<const PatternRow> entries, std::span<const PatternRow> moves);
    /// Whether held-back moves of buffer `id` are recorded as one dispatch of the pattern copy
    /// (record_moves_in_frame): at least kShaderRanges moves, none writing what another reads or
    /// writes (a swap removal's), with the range copies on.
    bool moves_in_frame(BufferId id, std::span<const ElementMove> moves) const;
    /// Records `moves` into the recording's command buffer as a pattern copy: an entry per move,
    /// a pattern per distinct length; after a barrier against all earlier work, also an
    /// engine's reads of the outputs moved.
    Status record_moves_in_frame(BufferId id, std::span<const ElementMove> moves);
    /// The moves into `cmd` through the scratch buffer (vkCmdCopyBuffer forbids overlapping
    /// regions), after a barrier against all earlier work, also an engine's reads.
    void record_moves(VkCommandBuffer cmd, BufferId id, std::span<const ElementMove> moves) const;
    /// record_moves one by one, each move one copy or pieces through scratch
    /// (HMSM_BATCH_TRANSFERS=0).
    void record_moves_one_by_one(VkCommandBuffer cmd, BufferId id, std::span<const ElementMove> moves) const;
    /// Checks `moves` of buffer `id` and returns the scratch bytes record_moves needs for them.
    Result<uint64_t> move_scratch_bytes(BufferId id, std::span<const ElementMove> moves) const;
    /// Whether read_ranges/write_ranges may copy `ranges` at once: batching on, an unsplit
    /// scene (a split one maps a range to pieces) and, for writes, ranges apart.
    bool copies_ranges_at_once(std::span<const ElementRange> ranges, bool writes) const;
    Status ensure_move_scratch(uint64_t bytes);
    /// Whether the moves of buffers `ids` go through the range copies (range_copy.h): batching
    /// on, and every buffer's words countable in 32 bits.
    bool copies_by_shader(std::span<const BufferId> ids) const;
    /// move_buffers through the range copies: per buffer and batch of its moves
    /// (plan_move_batches), a gather into the scratch and a scatter from it, all in one submission.
    Status shader_moves(std::span<const BufferMoves> moves);
    /// write_ranges through the scratch and the range copy's scatter (ranges apart, checked).
    Status shader_write(BufferId id, std::span<const ElementRange> ranges, const void* src, Scalar as);
    /// read_ranges through the range copy's gather into the scratch and one download of it.
    Status shader_read(BufferId id, std::span<const ElementRange> ranges, void* dst, Scalar as);
    /// Whether a read or write of `ranges` of buffer `id` goes through the range copy.
    bool transfers_by_shader(BufferId id, std::span<const ElementRange> ranges) const;
    /// One submission of range-copy dispatches between barriers against every earlier write;
    /// `record(cmd, barrier)` records them, barrier() between dispatches that depend on each
    /// other. The first error of `record` is returned; recording stops there.
    Status submit_copy_dispatches(const std::function<Status(VkCommandBuffer, const std::function<void()>&)>& record);
    /// write() inside a recording: the data goes to the ring, the copy into the command buffer.
    Status stage_write(BufferId id, uint64_t first, uint64_t count, const void* src, Scalar as);
    /// For a write of wind table elements [first, first + count) from `src` that reaches the
    /// device other than through the ring's copy of the table: the ring keeps the header it
    /// holds whole, or forgets the header it knew where it holds a part (frame_ring.h).
    void keep_wind_header(uint64_t first, uint64_t count, const void* src, Scalar as);
    /// Records `copy` of the ring slot's wind table into the engine's command buffer.
    void record_wind_copy(const FrameRing::WindCopy& copy);

    std::shared_ptr<Device> device_;
    std::unique_ptr<Pipelines> pipelines_;
    std::unique_ptr<Transfer> transfer_;
    /// The range copies of the batched transfers; null with HMSM_VULKAN_RANGE_COPIES=0 in the
    /// environment when the backend was made (copy commands of a region per range instead, for
    /// side-by-side measurements).
    std::unique_ptr<RangeCopier> range_copier_;
    std::array<Buffer, kBufferCount> buffers_;
    std::array<uint64_t, kBufferCount> element_counts_{};  // logical (read/write) counts
    Buffer move_scratch_;  // move_elements(), grown on demand
    bool batch_transfers_ = batch_transfers_enabled();  // element_moves.h
    bool pattern_copies_ = pattern_copies_enabled();    // element_moves.h
    /// Reads and writes of at least kShaderRanges ranges go through the range copy (a gather or
    /// a scatter: one dispatch) rather than a copy region per range; HMSM_VULKAN_SHADER_RANGES=0
    /// when the backend is made keeps copy regions (side-by-side measurements, docs/vulkan.md).
    static constexpr size_t kShaderRanges = 64;
    bool shader_ranges_ = true;
    uint64_t moves_recorded_as_copies_ = 0;
    uint64_t window_bytes_ = 0;  // vulkan_set_window_bytes() when the backend was made; 0: none
    uint64_t window_alignment_ = 0;
    std::unique_ptr<WindowPlan> plan_;
    std::unique_ptr<WindowSets> sets_;
    VkCommandPool pool_ = VK_NULL_HANDLE;
    std::array<Slot, 2> slots_;
    bool profiling_ = false;
    VulkanFault fault_ = VulkanFault::none;  // vulkan_inject_fault() when the backend was made
    uint32_t submissions_before_fault_ = 0;
    bool device_lost_ = false;
    PassTimes times_;
    VkCommandBuffer record_target_ = VK_NULL_HANDLE;
    std::unique_ptr<FrameRing> ring_;
    RecordingPlan recording_;  // the commands of a step of the last step program run
    RecordingPlan one_off_recording_;  // those of the last one-off program (prepare_one_off)
    RecordingPlan::Batching batching_;
    std::unique_ptr<RunTable> run_table_;
    std::unique_ptr<StepReplay> replay_;  // null: recorded steps go into the engine's buffer
    std::unique_ptr<ReadSlots> read_slots_;
    // request_read of an output past one allocation: read at the request into host memory.
    mutable std::array<std::vector<float>, kReadSlots> read_fallback_;
    mutable std::array<bool, kReadSlots> read_from_host_{};
    uint64_t recordings_ = 0;             // begin_recording calls
    uint64_t wind_copies_in_engine_buffers_ = 0;  // engine_copy_commands()
    uint64_t submissions_ = 0;
    bool in_instance_change_ = false;
    bool engine_recorded_ = false;  // record_steps has recorded into an engine's command buffer
    bool releasing_ = false;        // held-back changes being submitted or recorded
    /// Blocking steps hold instance changes back too (HMSM_VULKAN_HOLD_BACK=0: not), at most
    /// this many staged bytes, so that the ring's slots stay small.
    static constexpr uint64_t kBlockingHeldBytes = 16ull << 20;
    bool hold_back_blocking_ = blocking_hold_back_requested();
    uint64_t held_back_bytes_ = 0;
    std::vector<HeldBack> held_back_;
};

}  // namespace hmsm::detail::vk

namespace hmsm::detail {
/// True when `backend` is a Vulkan backend on a CPU driver such as lavapipe (`auto` skips it).
bool vulkan_backend_is_cpu_device(const Backend& backend);
}  // namespace hmsm::detail
