#include "recorder.h"

#include "device_buffer.h"

#include <algorithm>
#include <cstring>

namespace hmsm::detail::vk {

WorkgroupGrid workgroup_grid(uint64_t groups, const DeviceLimits& limits) {
    if (groups == 0) return {};
    uint64_t x = std::min<uint64_t>(groups, limits.max_workgroup_count[0]);
    uint64_t y = (groups + x - 1) / x;  // <= 2^26 / 65535 + 1, within the guaranteed 65535
    return {uint32_t(x), uint32_t(y)};
}

namespace {

/// Equal dispatches: the pass and every field of the constants (not the padding before params).
bool same_dispatch(const Dispatch& a, const Dispatch& b) {
    static_assert(offsetof(gpu::PassConstants, wind_slot) + sizeof(uint32_t) <= offsetof(gpu::PassConstants, params));
    constexpr size_t scalars = offsetof(gpu::PassConstants, wind_slot) + sizeof(uint32_t);
    return a.pass == b.pass && std::memcmp(&a.constants, &b.constants, scalars) == 0 &&
           std::memcmp(&a.constants.params, &b.constants.params, sizeof a.constants.params) == 0;
}

}  // namespace

bool RecordingPlan::holds(std::span<const Dispatch> program) const {
    if (program.size() != program_.size() || program.empty()) return false;
    for (size_t i = 0; i < program.size(); ++i)
        if (!same_dispatch(program[i], program_[i])) return false;
    return true;
}

Status RecordingPlan::prepare(const Device& device, Pipelines& pipelines, const Windows& windows,
                              std::span<const Dispatch> program) {
    if (holds(program)) return {};
    program_.clear();
    HMSM_TRY(pipelines.prepare(program));
    parts_.clear();
    for (const WindowPlan::Part& part : windows.plan.expand(program)) {
        const Dispatch& d = part.dispatch;
        Part p;
        p.pipeline = pipelines.pipeline_for(d).pipeline;
        p.set = windows.sets.set(part.segment);
        p.constants = d.constants;
        // One workgroup per instance for in-dispatch rounds, else one per HMSM_WORKGROUP_SIZE
        // threads.
        p.grid = workgroup_grid(launch_shape(d).workgroups, device.limits());
        p.reads = dispatch_reads(d);
        p.writes = dispatch_writes(d);
        p.reads_wind_slot = reads_wind_slot(d);
        p.last = part.last;
        parts_.push_back(p);
    }
    program_.assign(program.begin(), program.end());
    return {};
}

void record_steps(const Device& device, VkPipelineLayout layout, const RecordingPlan& plan, VkCommandBuffer cmd,
                  std::span<const RunStep> steps, VkQueryPool timestamps) {
    const VolkDeviceTable& vk = device.vk();
    const uint32_t queries = uint32_t(steps.size() * plan.dispatches() + 1);
    if (timestamps) vk.vkCmdResetQueryPool(cmd, timestamps, 0, queries);
    barrier_after_all_writes(device, cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                             VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT);
    if (timestamps) vk.vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, timestamps, 0);

    VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    barrier.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
    barrier.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT;
    uint32_t written = 0, read = 0;  // buffers touched since the last barrier (bit = BufferId)
    VkPipeline bound = VK_NULL_HANDLE;
    VkDescriptorSet bound_set = VK_NULL_HANDLE;
    uint32_t query = 1;
    for (const RunStep& step : steps) {
        for (const RecordingPlan::Part& part : plan.parts()) {
            if (((part.reads | part.writes) & written) || (part.writes & read)) {
                vk.vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                                        VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 1, &barrier, 0,
                                        nullptr, 0, nullptr);
                written = read = 0;
            }
            written |= part.writes;
            read |= part.reads;
            if (part.pipeline != bound) {
                vk.vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, part.pipeline);
                bound = part.pipeline;
            }
            if (part.set != bound_set) {
                vk.vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, layout, 0, 1, &part.set, 0, nullptr);
                bound_set = part.set;
            }
            if (part.reads_wind_slot) {
                gpu::PassConstants constants = part.constants;
                constants.wind_slot = step.wind_slot;
                vk.vkCmdPushConstants(cmd, layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(constants), &constants);
            } else {
                vk.vkCmdPushConstants(cmd, layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(part.constants),
                                      &part.constants);
            }
            if (part.grid.x) vk.vkCmdDispatch(cmd, part.grid.x, part.grid.y, 1);
            if (timestamps && part.last)
                vk.vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, timestamps, query++);
        }
    }
}

}  // namespace hmsm::detail::vk
