#include "recorder.h"

#include "device_buffer.h"

#include <algorithm>

namespace hmsm::detail::vk {

WorkgroupGrid workgroup_grid(uint64_t groups, const DeviceLimits& limits) {
    if (groups == 0) return {};
    uint64_t x = std::min<uint64_t>(groups, limits.max_workgroup_count[0]);
    uint64_t y = (groups + x - 1) / x;  // <= 2^26 / 65535 + 1, within the guaranteed 65535
    return {uint32_t(x), uint32_t(y)};
}

void record_steps(const Device& device, const Pipelines& pipelines, const Windows& windows,
                  VkCommandBuffer cmd, std::span<const Dispatch> program,
                  std::span<const RunStep> steps, VkQueryPool timestamps) {
    const VolkDeviceTable& vk = device.vk();
    const uint32_t queries = uint32_t(steps.size() * program.size() + 1);
    if (timestamps) vk.vkCmdResetQueryPool(cmd, timestamps, 0, queries);
    barrier_after_all_writes(device, cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                             VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT);
    // Each dispatch as its parts, one per segment of the scene it covers (windows.h).
    const std::vector<WindowPlan::Part> parts = windows.plan.expand(program);
    VkDescriptorSet bound_set = VK_NULL_HANDLE;
    if (timestamps) vk.vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, timestamps, 0);

    VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    barrier.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
    barrier.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT;
    uint32_t written = 0, read = 0;  // buffers touched since the last barrier (bit = BufferId)
    VkPipeline bound = VK_NULL_HANDLE;
    uint32_t query = 1;
    for (const RunStep& step : steps) {
        for (const WindowPlan::Part& part : parts) {
            const Dispatch& d = part.dispatch;
            const uint32_t reads = dispatch_reads(d), writes = dispatch_writes(d);
            if (((reads | writes) & written) || (writes & read)) {
                vk.vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                                        VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 1, &barrier, 0,
                                        nullptr, 0, nullptr);
                written = read = 0;
            }
            written |= writes;
            read |= reads;

            const Pipelines::Choice choice = pipelines.pipeline_for(d);
            if (choice.pipeline != bound) {
                vk.vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, choice.pipeline);
                bound = choice.pipeline;
            }
            if (VkDescriptorSet set = windows.sets.set(part.segment); set != bound_set) {
                vk.vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipelines.layout(), 0,
                                           1, &set, 0, nullptr);
                bound_set = set;
            }
            gpu::PassConstants constants = d.constants;
            if (reads_wind_slot(d)) constants.wind_slot = step.wind_slot;
            vk.vkCmdPushConstants(cmd, pipelines.layout(), VK_SHADER_STAGE_COMPUTE_BIT, 0,
                                  sizeof(constants), &constants);
            // One workgroup per instance for in-dispatch rounds, else one
            // per HMSM_WORKGROUP_SIZE threads.
            WorkgroupGrid grid = workgroup_grid(launch_shape(d).workgroups, device.limits());
            if (grid.x) vk.vkCmdDispatch(cmd, grid.x, grid.y, 1);
            if (timestamps && part.last)
                vk.vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, timestamps, query++);
        }
    }
}

}  // namespace hmsm::detail::vk
