// The seven compute pipelines (one per pass, SPIR-V embedded at build time; compose and
// root_positions also in larger workgroup sizes for in-dispatch rounds), their shared
// layout (descriptor set 0 with one storage buffer per BufferId, set 1 the run table of batched
// runs, push constants = gpu::PassConstants). The descriptor sets binding the scene's buffers
// are in windows.h, the run table's in run_table.h.
#pragma once

#include "device.h"
#include "device_buffer.h"

#include "../backend.h"
#include "../buffers.h"

#include <hmsm/pass.h>

#include <array>
#include <cstdint>
#include <memory>
#include <span>

namespace hmsm::detail::vk {

/// SPIR-V words of `pass`, compiled from shaders/glsl/NAME.comp.
std::span<const uint32_t> pass_spirv(Pass pass);

/// A descriptor set layout of `count` storage buffers, bindings 0 .. count - 1, for compute.
Status storage_buffer_set_layout(const Device& device, uint32_t count, VkDescriptorSetLayout& layout);
/// The compute pipeline of SPIR-V `code` (entry point main) with `layout`; where
/// `workgroup_size` is given, it sets specialization constant 0.
Result<VkPipeline> compute_pipeline(const Device& device, VkPipelineLayout layout, std::span<const uint32_t> code,
                                    const uint32_t* workgroup_size = nullptr);

class Pipelines {
public:
    static Result<std::unique_ptr<Pipelines>> create(const Device& device);
    ~Pipelines();

    /// The pipeline of `pass` with workgroups of HMSM_WORKGROUP_SIZE.
    VkPipeline pipeline(Pass pass) const { return pipelines_[uint32_t(pass)]; }
    /// The pipeline and workgroup size a dispatch runs with: in-dispatch pointer-jumping
    /// rounds use gpu::rounds_workgroup_size, capped at the device's
    /// limits. The pipeline must have been created by prepare().
    struct Choice {
        VkPipeline pipeline;
        uint32_t workgroup_size;
    };
    Choice pipeline_for(const Dispatch& dispatch) const;
    /// Creates the pipelines with other workgroup sizes that `program` needs (once each).
    Status prepare(std::span<const Dispatch> program);
    VkPipelineLayout layout() const { return layout_; }
    VkDescriptorSetLayout set_layout() const { return set_layout_; }
    /// Set HMSM_RUN_TABLE_SET: the run table's constants and first workgroups.
    VkDescriptorSetLayout table_set_layout() const { return table_set_layout_; }
    static constexpr uint32_t kRunTableBindings = 2;
    static constexpr uint32_t kStorageBuffersPerStage = kBufferCount + kRunTableBindings;

private:
    explicit Pipelines(const Device& device) : device_(device) {}

    const Device& device_;
    VkDescriptorSetLayout set_layout_ = VK_NULL_HANDLE;
    VkDescriptorSetLayout table_set_layout_ = VK_NULL_HANDLE;
    VkPipelineLayout layout_ = VK_NULL_HANDLE;
    Result<VkPipeline> create_pipeline(Pass pass, uint32_t workgroup_size) const;
    /// A pipeline of `code` with specialization constant 0 (the workgroup size); no
    /// specialization when `specialized` is false.
    Result<VkPipeline> create_pipeline(std::span<const uint32_t> code, bool specialized,
                                       uint32_t workgroup_size) const;
    uint32_t per_instance_size(const Dispatch& dispatch) const;

    std::array<VkPipeline, kPassCount> pipelines_{};
    /// Pipelines of a workgroup per instance, by size: [compose, root_positions (in-dispatch
    /// rounds), integrate (instance sweeps)][log2(size / 64)].
    static constexpr uint32_t kRoundsSizes = 5;  // 64 .. HMSM_MAX_ROUNDS_WORKGROUP_SIZE
    std::array<std::array<VkPipeline, kRoundsSizes>, 3> rounds_pipelines_{};
};

}  // namespace hmsm::detail::vk
