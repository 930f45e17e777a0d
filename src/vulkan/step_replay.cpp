#include "step_replay.h"

#include "vk_error.h"

#include <atomic>
#include <cstdlib>
#include <string_view>

namespace hmsm::detail {
namespace {
std::atomic<int> g_step_replay{0};  // 0: the environment decides, 1 on, 2 off
}  // namespace

void vulkan_set_step_replay(std::optional<bool> enabled) { g_step_replay = enabled ? (*enabled ? 1 : 2) : 0; }

namespace vk {

bool step_replay_requested() {
    if (int hook = g_step_replay.load()) return hook == 1;
    const char* env = std::getenv("HMSM_VULKAN_REPLAY_STEPS");
    return !(env && std::string_view(env) == "0");
}

Result<std::unique_ptr<StepReplay>> StepReplay::create(const Device& device, uint32_t frames) {
    std::unique_ptr<StepReplay> replay(new StepReplay(device));
    VkCommandPoolCreateInfo pool{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pool.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    pool.queueFamilyIndex = device.queue_family();
    HMSM_VK_TRY(device.vk().vkCreateCommandPool(device.handle(), &pool, nullptr, &replay->pool_));
    replay->frames_.resize(frames);
    for (std::vector<Secondary>& slot : replay->frames_) slot.reserve(kSecondariesPerFrame);
    return replay;
}

StepReplay::~StepReplay() {
    // Destroying the pool frees its command buffers.
    if (pool_) device_.vk().vkDestroyCommandPool(device_.handle(), pool_, nullptr);
}

bool StepReplay::holds(const Secondary& s, const Contents& c) {
    if (s.plan_generation != c.plan.generation() || s.table_set != c.table_set ||
        s.wind_slots.size() != c.steps.size() || s.wind.src != c.wind.src || s.wind.bytes != c.wind.bytes)
        return false;
    for (size_t k = 0; k < c.steps.size(); ++k)
        if (s.wind_slots[k] != c.steps[k].wind_slot) return false;
    return true;
}

Status StepReplay::record_secondary(Secondary& s, VkPipelineLayout layout, const Contents& c) {
    const VolkDeviceTable& vk = device_.vk();
    s.plan_generation = 0;  // holds nothing until it is recorded whole
    if (!s.command_buffer) {
        VkCommandBufferAllocateInfo allocate{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
        allocate.commandPool = pool_;
        allocate.level = VK_COMMAND_BUFFER_LEVEL_SECONDARY;
        allocate.commandBufferCount = 1;
        HMSM_VK_TRY(vk.vkAllocateCommandBuffers(device_.handle(), &allocate, &s.command_buffer));
    }
    // Outside a render pass: no render pass, subpass or framebuffer to inherit, no queries.
    VkCommandBufferInheritanceInfo inheritance{VK_STRUCTURE_TYPE_COMMAND_BUFFER_INHERITANCE_INFO};
    VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    begin.pInheritanceInfo = &inheritance;
    HMSM_VK_TRY(vk.vkBeginCommandBuffer(s.command_buffer, &begin));
    if (c.wind.bytes) FrameRing::record_wind_copy(device_, s.command_buffer, c.wind, c.wind_table);
    record_steps(device_, layout, c.plan, s.command_buffer, c.steps, VK_NULL_HANDLE, c.table_set);
    HMSM_VK_TRY(vk.vkEndCommandBuffer(s.command_buffer));
    s.plan_generation = c.plan.generation();
    s.table_set = c.table_set;
    s.wind = c.wind;
    s.wind_slots.resize(c.steps.size());
    for (size_t k = 0; k < c.steps.size(); ++k) s.wind_slots[k] = c.steps[k].wind_slot;
    ++secondaries_recorded_;
    return {};
}

Status StepReplay::record(VkCommandBuffer primary, uint32_t frame, uint64_t recording, VkPipelineLayout layout,
                          const RecordingPlan& plan, std::span<const RunStep> steps, VkDescriptorSet table_set,
                          const FrameRing::WindCopy* wind, VkBuffer wind_table) {
    const Contents contents{plan, steps, table_set, wind ? *wind : FrameRing::WindCopy{}, wind_table};
    std::vector<Secondary>& slot = frames_[frame];
    Secondary* chosen = nullptr;
    for (Secondary& s : slot)
        if (s.used_in != recording && holds(s, contents)) {
            chosen = &s;
            break;
        }
    if (!chosen) {
        // One to record: a secondary holding an older plan first, then a new one while the
        // slot has room, else any this recording has not executed.
        for (Secondary& s : slot)
            if (s.used_in != recording && s.plan_generation != plan.generation()) {
                chosen = &s;
                break;
            }
        if (!chosen && slot.size() < kSecondariesPerFrame) chosen = &slot.emplace_back();
        if (!chosen)
            for (Secondary& s : slot)
                if (s.used_in != recording) {
                    chosen = &s;
                    break;
                }
        if (!chosen) {
            if (wind) FrameRing::record_wind_copy(device_, primary, *wind, wind_table);
            record_steps(device_, layout, plan, primary, steps, VK_NULL_HANDLE, table_set);
            return {};
        }
        HMSM_TRY(record_secondary(*chosen, layout, contents));
    }
    chosen->used_in = recording;
    device_.vk().vkCmdExecuteCommands(primary, 1, &chosen->command_buffer);
    ++replays_;
    return {};
}

}  // namespace vk
}  // namespace hmsm::detail
