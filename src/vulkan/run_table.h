// The run table of the Vulkan backend: where the dispatches of a batched run (step_program.h
// dispatch_batches; run_table_layout.h) find their constants. A run of
// dispatches of one pass over many instance groups is recorded as one vkCmdDispatch; its
// workgroups look their dispatch up here (common.glsl load_constants). The table depends only
// on the program and the scene's segments, so it is written when the step program changes and
// read by every step and every recorded frame until then; the step's wind slot travels in the
// push constants.
//
// One device-local buffer holds the constants (gpu::PassConstants per entry) and, after them,
// the first workgroup of each entry's dispatch in its launch, bound as descriptor set
// HMSM_RUN_TABLE_SET. It grows by replacement: frames in flight may still read the old buffer,
// so it is kept until the recording that replaced it has completed under the ring rule
// (docs/vulkan.md), or until a submission of hmsm's own, which every recorded frame precedes.
#pragma once

#include "device.h"
#include "device_buffer.h"
#include "frame_ring.h"

#include "../backend.h"
#include "../common/run_table_layout.h"

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <vector>

namespace hmsm::detail {
/// Test hook: backends created afterwards batch runs when `enabled`, or record each dispatch
/// alone, and start a new launch where a batched one would pass `max_workgroups` workgroups
/// (0: the device's maxComputeWorkGroupCount). Without the hook (`enabled` empty), the
/// environment variable HMSM_VULKAN_BATCH_RUNS decides (0 off, 1 on), else the device: a GPU
/// batches, a CPU driver does not (llvmpipe runs the looked-up constants lane by lane, so the
/// branches and the in-dispatch rounds' barrier loops cost more there than the launches saved).
void vulkan_set_batch_runs(std::optional<bool> enabled, uint64_t max_workgroups = 0);
}  // namespace hmsm::detail

namespace hmsm::detail::vk {

/// Whether backends created now batch runs (vulkan_set_batch_runs, HMSM_VULKAN_BATCH_RUNS);
/// empty: as the device prefers.
std::optional<bool> requested_batch_runs();
/// The most workgroups of a batched launch the hook asks for (0: the device's limit).
uint64_t requested_batch_workgroups();

class RunTable {
public:
    /// A table of `entries` entries to start with (at least one: the set is bound by every
    /// recording, batched or not).
    static Result<std::unique_ptr<RunTable>> create(const Device& device, VkDescriptorSetLayout layout,
                                                    uint32_t entries = 64);
    ~RunTable();

    VkDescriptorSet set() const { return current_.set; }
    /// Writes the table now (a submission of its own that waits): `constants` and
    /// `first_workgroups` have one element per entry.
    Status upload(Transfer& transfer, std::span<const gpu::PassConstants> constants,
                  std::span<const uint32_t> first_workgroups);
    /// Stages the table in the ring's current slot; the copies go with the ring's next
    /// record_copies(), ahead of the steps that read it.
    Status stage(FrameRing& ring, std::span<const gpu::PassConstants> constants,
                 std::span<const uint32_t> first_workgroups);
    /// A recording begins: buffers replaced `frames` recordings ago are free.
    void next_recording(uint32_t frames);
    /// Everything recorded before has completed (a submission of hmsm's own has been waited for).
    void release_replaced();

private:
    struct Storage {
        Buffer buffer;
        VkDescriptorPool pool = VK_NULL_HANDLE;
        VkDescriptorSet set = VK_NULL_HANDLE;
        uint32_t capacity = 0;
        VkDeviceSize workgroups_offset = 0;  // byte offset of the first workgroups
        uint64_t replaced_at = 0;            // the recording that replaced it
    };

    RunTable(const Device& device, VkDescriptorSetLayout layout) : device_(device), layout_(layout) {}
    Result<Storage> create_storage(uint32_t entries) const;
    void destroy(Storage& storage) const;
    /// Room for `entries` entries, replacing the buffer by a larger one where needed.
    Status reserve(uint32_t entries);

    const Device& device_;
    VkDescriptorSetLayout layout_;
    Storage current_;
    std::vector<Storage> replaced_;
    uint64_t recordings_ = 0;
};

}  // namespace hmsm::detail::vk
