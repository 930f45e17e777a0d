// The seven compute pipelines (one per pass, SPIR-V embedded at build time; compose and
// root_positions also in larger workgroup sizes for in-dispatch rounds), the fused pipelines of
// Composition::fused (one per workgroup size and shared-memory size), their shared
// layout (descriptor set 0 with one storage buffer per BufferId, push constants =
// gpu::PassConstants). The descriptor sets binding the scene's buffers are in windows.h.
#pragma once

#include "device.h"
#include "device_buffer.h"

#include "../backend.h"
#include "../buffers.h"

#include <hmsm/pass.h>

#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <span>
#include <utility>

namespace hmsm::detail::vk {

/// SPIR-V words of `pass`, compiled from shaders/glsl/NAME.comp.
std::span<const uint32_t> pass_spirv(Pass pass);

class Pipelines {
public:
    static Result<std::unique_ptr<Pipelines>> create(const Device& device);
    ~Pipelines();

    /// The pipeline of `pass` with workgroups of HMSM_WORKGROUP_SIZE.
    VkPipeline pipeline(Pass pass) const { return pipelines_[uint32_t(pass)]; }
    /// The pipeline and workgroup size a dispatch runs with: in-dispatch pointer-jumping
    /// rounds and fused dispatches use gpu::rounds_workgroup_size, capped at the device's
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

private:
    explicit Pipelines(const Device& device) : device_(device) {}

    const Device& device_;
    VkDescriptorSetLayout set_layout_ = VK_NULL_HANDLE;
    VkPipelineLayout layout_ = VK_NULL_HANDLE;
    Result<VkPipeline> create_pipeline(Pass pass, uint32_t workgroup_size) const;
    /// A pipeline of `code` with specialization constants 0 (the workgroup size) and, for the
    /// fused shader, 1 (its shared floats); no specialization when `specialized` is false.
    Result<VkPipeline> create_pipeline(std::span<const uint32_t> code, bool specialized,
                                       uint32_t workgroup_size, uint32_t shared_floats) const;
    uint32_t rounds_size(const Dispatch& dispatch) const;
    /// The fused shader's shared floats for a dispatch: HMSM_FUSED_SHARED_FLOATS_PER_CHAIN per
    /// chain where that fits fused_shared_bytes_, else 1 (the rounds in device memory).
    uint32_t fused_shared_floats(const Dispatch& dispatch) const;
    using FusedKey = std::pair<uint32_t, uint32_t>;  // (workgroup size, shared floats)
    FusedKey fused_key(const Dispatch& dispatch) const {
        return {rounds_size(dispatch), fused_shared_floats(dispatch)};
    }

    std::array<VkPipeline, kPassCount> pipelines_{};
    /// In-dispatch rounds pipelines: [compose, root_positions][log2(size / 64)].
    static constexpr uint32_t kRoundsSizes = 5;  // 64 .. HMSM_MAX_ROUNDS_WORKGROUP_SIZE
    std::array<std::array<VkPipeline, kRoundsSizes>, 2> rounds_pipelines_{};
    std::map<FusedKey, VkPipeline> fused_pipelines_;
    /// Shared memory a fused workgroup may take (fused_shared_limit at creation).
    uint64_t fused_shared_bytes_ = 0;
};

}  // namespace hmsm::detail::vk
