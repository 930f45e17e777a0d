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
    struct Part {
        VkPipeline pipeline = VK_NULL_HANDLE;
        VkDescriptorSet set = VK_NULL_HANDLE;
        gpu::PassConstants constants{};
        WorkgroupGrid grid;
        uint32_t reads = 0, writes = 0;  // buffers (bit = BufferId)
        bool reads_wind_slot = false;    // constants.wind_slot is the step's
        bool last = true;                // the last part of its dispatch (timestamps)
    };

    /// Builds the plan of `program` (creating the pipelines it needs) unless it already holds
    /// that program's.
    Status prepare(const Device& device, Pipelines& pipelines, const Windows& windows,
                   std::span<const Dispatch> program);
    /// Forgets the plan (the scene's buffers or descriptor sets changed).
    void clear() { program_.clear(); }
    std::span<const Part> parts() const { return parts_; }
    /// Dispatches of the program (timestamps: one after each).
    size_t dispatches() const { return program_.size(); }

private:
    bool holds(std::span<const Dispatch> program) const;

    std::vector<Dispatch> program_;
    std::vector<Part> parts_;
};

/// Records steps.size() steps of `plan` into `cmd` (already begun). Starts with a barrier
/// against all earlier shader and transfer writes. With a `timestamps` pool, writes timestamp 0
/// before the first dispatch and timestamp j + 1 after dispatch j (the pool must hold
/// steps.size() * plan.dispatches() + 1 queries; they are reset here). Parts of a split scene's
/// dispatch are tracked for hazards like dispatches, so they are separated by barriers.
void record_steps(const Device& device, VkPipelineLayout layout, const RecordingPlan& plan, VkCommandBuffer cmd,
                  std::span<const RunStep> steps, VkQueryPool timestamps);

}  // namespace hmsm::detail::vk
