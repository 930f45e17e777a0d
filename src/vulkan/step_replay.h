// Steps recorded into an engine's command buffer (hmsm/vulkan.h record_steps) as replays: the
// commands of a run of steps (recorder.h record_steps: the leading barrier, the run table's
// set, every part's barrier, pipeline, descriptor set, push constants and dispatch) depend only
// on the recording plan, the run table's set and the steps' wind-table slots, so they are
// recorded once into a secondary command buffer and each later frame executes it with one
// vkCmdExecuteCommands. What changes from frame to frame reaches the device through the ring
// (frame_ring.h): the wind table (the step slots with the load half and the fades' clock, the
// header with the force fields) by a copy from the slot's copy of the table that the secondary
// itself begins with, so a steady frame records one command into the engine's primary;
// instance settings and other writes by the ring's copies, which the primary records ahead of
// the replay.
//
// Each frame of the ring (frame_ring.h) has secondaries of its own: under the ring rule the
// primary that executed a frame slot's secondaries has completed when the ring comes round to
// that slot again, so a secondary is never pending while it is executed again or re-recorded,
// and none needs VK_COMMAND_BUFFER_USAGE_SIMULTANEOUS_USE_BIT. A secondary is recorded again
// only when what it replays changed (a new plan: a live reshape, a switch of levels, a fade
// that ended, an upload or growth; a replaced run table; other step slots).
//
// The secondaries come from a pool of the simulation's queue family: the engine's primary must
// come from a pool of that family too (vkCmdExecuteCommands requires it) and be outside a render
// pass (the secondaries inherit none).
#pragma once

#include "device.h"
#include "frame_ring.h"
#include "recorder.h"

#include "../backend.h"

#include <memory>
#include <optional>
#include <span>
#include <vector>

namespace hmsm::detail {
/// Test hook: backends created afterwards replay recorded steps from secondary command buffers
/// when `enabled`, or record every step's commands into the engine's command buffer. Without
/// the hook (`enabled` empty), the environment variable HMSM_VULKAN_REPLAY_STEPS decides (0
/// off); replay is on by default.
void vulkan_set_step_replay(std::optional<bool> enabled);
}  // namespace hmsm::detail

namespace hmsm::detail::vk {

/// Whether backends created now replay recorded steps (vulkan_set_step_replay).
bool step_replay_requested();

class StepReplay {
public:
    /// Secondaries for `frames` frames in flight, from a pool of the device's queue family.
    static Result<std::unique_ptr<StepReplay>> create(const Device& device, uint32_t frames);
    ~StepReplay();

    /// Records `steps` of `plan` into `primary` as one vkCmdExecuteCommands of a secondary of
    /// ring slot `frame`, recording that secondary first where it does not hold these steps;
    /// with `wind`, the secondary copies the slot's wind table to `wind_table` first.
    /// `recording` names the engine recording (record_steps call) the primary belongs to: a
    /// secondary executes at most once per recording. Past kSecondariesPerFrame runs in one
    /// recording the steps are recorded into `primary` directly.
    Status record(VkCommandBuffer primary, uint32_t frame, uint64_t recording, VkPipelineLayout layout,
                  const RecordingPlan& plan, std::span<const RunStep> steps, VkDescriptorSet table_set,
                  const FrameRing::WindCopy* wind, VkBuffer wind_table);
    /// Secondaries recorded so far (a test hook: a steady frame loop records none).
    uint64_t secondaries_recorded() const { return secondaries_recorded_; }
    /// vkCmdExecuteCommands recorded so far (a test hook).
    uint64_t replays() const { return replays_; }

    /// Runs of one recording that each get a secondary of their own (record_steps of more than
    /// 255 steps, or steps between fades' folds, run the program more than once).
    static constexpr size_t kSecondariesPerFrame = 4;

private:
    struct Secondary {
        VkCommandBuffer command_buffer = VK_NULL_HANDLE;
        uint64_t plan_generation = 0;  // 0: holds nothing
        VkDescriptorSet table_set = VK_NULL_HANDLE;
        std::vector<uint32_t> wind_slots;  // the steps it records, by their wind-table slot
        FrameRing::WindCopy wind;          // the wind table copy it begins with (bytes 0: none)
        uint64_t used_in = 0;              // the last recording that executed it (0: none)
    };

    explicit StepReplay(const Device& device) : device_(device) {}
    /// What a secondary records: the plan's steps, the run table's set and the wind copy.
    struct Contents {
        const RecordingPlan& plan;
        std::span<const RunStep> steps;
        VkDescriptorSet table_set;
        FrameRing::WindCopy wind;
        VkBuffer wind_table;
    };
    static bool holds(const Secondary& s, const Contents& c);
    Status record_secondary(Secondary& s, VkPipelineLayout layout, const Contents& c);

    const Device& device_;
    VkCommandPool pool_ = VK_NULL_HANDLE;
    std::vector<std::vector<Secondary>> frames_;  // per ring slot, up to kSecondariesPerFrame
    uint64_t secondaries_recorded_ = 0;
    uint64_t replays_ = 0;
};

}  // namespace hmsm::detail::vk
