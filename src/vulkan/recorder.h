// Records steps of the step program into a command buffer: every dispatch of every step, a
// compute->compute barrier only where a dispatch touches a buffer that an earlier dispatch
// since the last barrier wrote (read-after-write, write-after-write) or writes one it read
// (write-after-read), from pass_reads/pass_writes. Hazards are tracked per buffer, so the
// pointer-jumping rounds of compose and root_positions (which read the half the previous round
// wrote) and dispatches of several instance groups writing the same buffer are separated too.
#pragma once

#include "device.h"
#include "pipelines.h"
#include "windows.h"

#include "../backend.h"

#include <span>

namespace hmsm::detail::vk {

/// `groups` workgroups as a 1-D grid while it fits maxComputeWorkGroupCount[0], else 2-D (the
/// shaders linearize gl_WorkGroupID); {0, 0} for none.
struct WorkgroupGrid {
    uint32_t x = 0, y = 0;
};
WorkgroupGrid workgroup_grid(uint64_t groups, const DeviceLimits& limits);

/// Records steps.size() steps of `program` into `cmd` (already begun); `pipelines` must have
/// been prepared for `program` (Pipelines::prepare). Starts with a barrier
/// against all earlier shader and transfer writes. With a `timestamps` pool, writes timestamp 0
/// before the first dispatch and timestamp j + 1 after dispatch j (the pool must hold
/// steps.size() * program.size() + 1 queries; they are reset here). A dispatch of a split
/// scene is recorded as one part per segment it overlaps (windows.h), each with its segment's
/// descriptor set; hazards are tracked per part, so the parts are separated by barriers.
void record_steps(const Device& device, const Pipelines& pipelines, const Windows& windows,
                  VkCommandBuffer cmd, std::span<const Dispatch> program,
                  std::span<const RunStep> steps, VkQueryPool timestamps);

}  // namespace hmsm::detail::vk
