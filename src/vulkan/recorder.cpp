#include "recorder.h"

#include "device_buffer.h"

#include "../step_program.h"
#include "../common/run_table_layout.h"

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

bool RecordingPlan::holds(std::span<const Dispatch> program, Batching batching, uint64_t program_id) const {
    if (program.size() != program_.size() || program.empty()) return false;
    if (batching.batch_runs != batching_.batch_runs || batching.max_workgroups != batching_.max_workgroups)
        return false;
    if (program_id != 0 && program_id == program_id_) return true;
    for (size_t i = 0; i < program.size(); ++i)
        if (!same_dispatch(program[i], program_[i])) return false;
    return true;
}

Result<bool> RecordingPlan::prepare(const Device& device, Pipelines& pipelines, const Windows& windows,
                                    std::span<const Dispatch> program, Batching batching, uint64_t program_id) {
    if (holds(program, batching, program_id)) {
        program_id_ = program_id;
        return false;
    }
    clear();
    HMSM_TRY(pipelines.prepare(program));
    parts_.clear();
    timestamp_passes_.clear();
    launches_ = 0;
    table_constants_.clear();
    table_first_workgroups_.clear();
    batching_ = batching;
    if (batching.batch_runs) {
        for (std::span<const Dispatch> run : dispatch_batches(program)) add_run(device, pipelines, windows, run);
    } else {
        for (size_t i = 0; i < program.size(); ++i) add_run(device, pipelines, windows, program.subspan(i, 1));
    }
    program_.assign(program.begin(), program.end());
    program_id_ = program_id;
    ++generation_;
    return true;
}

void RecordingPlan::add_part(Part part) {
    if (part.grid.x) ++launches_;
    if (part.timed) timestamp_passes_.push_back(part.pass);
    parts_.push_back(part);
}

void RecordingPlan::add_run(const Device& device, const Pipelines& pipelines, const Windows& windows,
                            std::span<const Dispatch> run) {
    const DeviceLimits& limits = device.limits();
    const std::vector<WindowPlan::Part> expanded = windows.plan.expand(run);
    auto alone = [&](const WindowPlan::Part& part, bool timed) {
        const Dispatch& d = part.dispatch;
        Part p;
        p.pipeline = pipelines.pipeline_for(d).pipeline;
        p.set = windows.sets.set(part.segment);
        p.constants = d.constants;
        // One workgroup per instance for in-dispatch rounds, else one per HMSM_WORKGROUP_SIZE
        // threads.
        p.grid = workgroup_grid(launch_shape(d).workgroups, limits);
        p.reads = dispatch_reads(d);
        p.writes = dispatch_writes(d);
        p.reads_wind_slot = reads_wind_slot(d);
        p.timed = timed;
        p.pass = d.pass;
        add_part(p);
    };
    if (run.size() == 1) {
        for (const WindowPlan::Part& part : expanded) alone(part, part.last);
        return;
    }
    // The launches of a run: its parts by segment (descriptor set) and pipeline (workgroup
    // size), in instance order within each (the run's dispatches share no state, so their order
    // is free), cut where a launch would pass the workgroup count it may have. Parts without
    // workgroups run nothing and are left out.
    uint64_t most = batching_.max_workgroups
                        ? batching_.max_workgroups
                        : uint64_t(limits.max_workgroup_count[0]) * limits.max_workgroup_count[1];
    most = std::min<uint64_t>(most, UINT32_MAX);
    struct Member {
        const WindowPlan::Part* part;
        uint32_t workgroup_size;
        uint64_t workgroups;
    };
    std::vector<Member> order;
    order.reserve(expanded.size());
    for (const WindowPlan::Part& part : expanded)
        if (const uint64_t count = launch_shape(part.dispatch).workgroups)
            order.push_back({&part, pipelines.pipeline_for(part.dispatch).workgroup_size, count});
    std::stable_sort(order.begin(), order.end(), [](const Member& a, const Member& b) {
        return a.part->segment != b.part->segment ? a.part->segment < b.part->segment
                                                  : a.workgroup_size < b.workgroup_size;
    });
    std::vector<const WindowPlan::Part*> members;
    uint64_t workgroups = 0;
    auto launch = [&] {
        if (members.size() == 1) alone(*members.front(), true);
        if (members.size() > 1) {
            const Dispatch& first = members.front()->dispatch;
            Part p;
            p.pipeline = pipelines.pipeline_for(first).pipeline;
            p.set = windows.sets.set(members.front()->segment);
            p.constants.kind = HMSM_DISPATCH_RUN_TABLE;
            p.constants.instance_begin = uint32_t(table_constants_.size());
            p.constants.element_count = uint32_t(members.size());
            uint64_t total = 0;
            for (const WindowPlan::Part* m : members) {
                const Dispatch& d = m->dispatch;
                table_constants_.push_back(d.constants);
                table_first_workgroups_.push_back(uint32_t(total));
                total += launch_shape(d).workgroups;
                p.reads |= dispatch_reads(d);
                p.writes |= dispatch_writes(d);
                p.reads_wind_slot = p.reads_wind_slot || reads_wind_slot(d);
            }
            p.grid = workgroup_grid(total, limits);
            p.pass = first.pass;
            add_part(p);
        }
        members.clear();
        workgroups = 0;
    };
    for (size_t i = 0; i < order.size(); ++i) {
        const Member& m = order[i];
        if (i > 0 && (order[i - 1].part->segment != m.part->segment ||
                      order[i - 1].workgroup_size != m.workgroup_size || workgroups + m.workgroups > most))
            launch();
        members.push_back(m.part);
        workgroups += m.workgroups;
    }
    launch();
}

void record_steps(const Device& device, VkPipelineLayout layout, const RecordingPlan& plan, VkCommandBuffer cmd,
                  std::span<const RunStep> steps, VkQueryPool timestamps, VkDescriptorSet table_set) {
    const VolkDeviceTable& vk = device.vk();
    const uint32_t queries = uint32_t(steps.size() * plan.timestamp_passes().size() + 1);
    if (timestamps) vk.vkCmdResetQueryPool(cmd, timestamps, 0, queries);
    vk.vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, layout, HMSM_RUN_TABLE_SET, 1, &table_set, 0,
                               nullptr);
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
            if (timestamps && part.timed)
                vk.vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, timestamps, query++);
        }
    }
}

}  // namespace hmsm::detail::vk
