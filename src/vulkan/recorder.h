// Records steps of the step program into a command buffer: every dispatch of every step, a
// compute->compute barrier only where a dispatch touches a buffer that an earlier dispatch
// since the last barrier wrote (read-after-write, write-after-write) or writes one it read
// (write-after-read), from pass_reads/pass_writes. Hazards are tracked per buffer, so the
// pointer-jumping rounds of compose and root_positions (which read the half the previous round
// wrote) and dispatches of several instance groups writing the same buffer are separated too.
//
// What a step records depends only on the program and the scene's layout, so it is computed
// once (RecordingPlan) and each recording replays it: one frame's record_steps is then a run
// of vkCmd calls without allocation or lookup.
//
// Batched runs: each run of dispatches that step_program.h dispatch_batches finds (one pass,
// kind, round and halves over many instance groups) is recorded as one vkCmdDispatch per
// segment and pipeline (in-dispatch rounds take a workgroup size per model), split further
// where the launch would pass the device's workgroup count. Its dispatches' constants go to
// the run table (run_table.h) and each workgroup finds its own (common.glsl); a dispatch alone
// keeps its push constants.
#pragma once

#include "device.h"
#include "pipelines.h"
#include "windows.h"

#include "../backend.h"

#include <span>
#include <vector>

namespace hmsm::detail::vk {

/// `groups` workgroups as a 1-D grid while it fits maxComputeWorkGroupCount[0], else 2-D (the
/// shaders linearize gl_WorkGroupID); {0, 0} for none.
struct WorkgroupGrid {
    uint32_t x = 0, y = 0;
};
WorkgroupGrid workgroup_grid(uint64_t groups, const DeviceLimits& limits);

/// The commands of one step of a program: each dispatch as its parts, one per segment of the
/// scene it covers (windows.h), with the pipeline, descriptor set, constants and grid each part
/// is recorded with. Valid while the pipelines and the descriptor sets it was built from live.
class RecordingPlan {
public:
    /// A dispatch alone, or a batched launch (constants.kind HMSM_DISPATCH_RUN_TABLE).
    struct Part {
        VkPipeline pipeline = VK_NULL_HANDLE;
        VkDescriptorSet set = VK_NULL_HANDLE;
        gpu::PassConstants constants{};
        WorkgroupGrid grid;
        uint32_t reads = 0, writes = 0;  // buffers (bit = BufferId)
        bool reads_wind_slot = false;    // constants.wind_slot is the step's
        bool timed = true;               // a timestamp follows (the end of a dispatch or launch)
        Pass pass = Pass::wind_force;
    };

    /// How runs are batched: `batch_runs` off records every dispatch alone; a batched launch
    /// has at most `max_workgroups` workgroups (0: the device's maxComputeWorkGroupCount).
    struct Batching {
        bool batch_runs = true;
        uint64_t max_workgroups = 0;
    };

    /// Builds the plan of `program` (creating the pipelines it needs) unless it already holds
    /// that program's (known by a non-zero `program_id` it was built or last held with, else by
    /// comparing the dispatches; Backend::run); true when it built one (the run table then has
    /// new contents).
    Result<bool> prepare(const Device& device, Pipelines& pipelines, const Windows& windows,
                         std::span<const Dispatch> program, Batching batching, uint64_t program_id = 0);
    /// Forgets the plan (the scene's buffers or descriptor sets changed).
    void clear() {
        program_.clear();
        program_id_ = 0;
    }
    std::span<const Part> parts() const { return parts_; }
    /// Names what prepare() last built: a different number after each build (0: nothing built),
    /// so commands recorded from one plan know when they are stale (step_replay.h).
    uint64_t generation() const { return program_.empty() ? 0 : generation_; }
    /// The pass of each timestamp after the first, in the order a step writes them.
    std::span<const Pass> timestamp_passes() const { return timestamp_passes_; }
    /// vkCmdDispatch calls per step.
    size_t launches() const { return launches_; }
    /// The run table (run_table.h): the constants of every batched dispatch, and the first
    /// workgroup of its launch that runs it.
    std::span<const gpu::PassConstants> table_constants() const { return table_constants_; }
    std::span<const uint32_t> table_first_workgroups() const { return table_first_workgroups_; }

private:
    bool holds(std::span<const Dispatch> program, Batching batching, uint64_t program_id) const;
    /// Appends the parts of `run` (consecutive dispatches that dispatch_batches joins).
    void add_run(const Device& device, const Pipelines& pipelines, const Windows& windows,
                 std::span<const Dispatch> run);
    void add_part(Part part);

    std::vector<Dispatch> program_;
    uint64_t program_id_ = 0;  // the id program_ was built or last held with (0: none)
    uint64_t generation_ = 0;  // builds so far
    Batching batching_;
    std::vector<Part> parts_;
    std::vector<Pass> timestamp_passes_;
    size_t launches_ = 0;
    std::vector<gpu::PassConstants> table_constants_;
    std::vector<uint32_t> table_first_workgroups_;
};

/// Records steps.size() steps of `plan` into `cmd` (already begun), with `table_set` (the run
/// table's descriptor set) bound. Starts with a barrier against all earlier shader and transfer
/// writes. With a `timestamps` pool, writes timestamp 0 before the first dispatch and timestamp
/// j + 1 after the j-th timed part (the pool must hold steps.size() *
/// plan.timestamp_passes().size() + 1 queries; they are reset here). Parts of a split scene's
/// dispatch are tracked for hazards like dispatches, so they are separated by barriers.
void record_steps(const Device& device, VkPipelineLayout layout, const RecordingPlan& plan, VkCommandBuffer cmd,
                  std::span<const RunStep> steps, VkQueryPool timestamps, VkDescriptorSet table_set);

}  // namespace hmsm::detail::vk
