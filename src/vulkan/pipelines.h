// The seven compute pipelines (one per pass, SPIR-V embedded at build time), their shared
// layout (descriptor set 0 with one storage buffer per BufferId, push constants =
// gpu::PassConstants). The descriptor sets binding the scene's buffers are in windows.h.
#pragma once

#include "device.h"
#include "device_buffer.h"

#include "../buffers.h"

#include <hmsm/pass.h>

#include <array>
#include <cstdint>
#include <memory>
#include <span>

namespace hmsm::detail::vk {

/// SPIR-V words of `pass`, compiled from shaders/glsl/NAME.comp.
std::span<const uint32_t> pass_spirv(Pass pass);

class Pipelines {
public:
    static Result<std::unique_ptr<Pipelines>> create(const Device& device);
    ~Pipelines();

    VkPipeline pipeline(Pass pass) const { return pipelines_[uint32_t(pass)]; }
    VkPipelineLayout layout() const { return layout_; }
    VkDescriptorSetLayout set_layout() const { return set_layout_; }

private:
    explicit Pipelines(const Device& device) : device_(device) {}

    const Device& device_;
    VkDescriptorSetLayout set_layout_ = VK_NULL_HANDLE;
    VkPipelineLayout layout_ = VK_NULL_HANDLE;
    std::array<VkPipeline, kPassCount> pipelines_{};
};

}  // namespace hmsm::detail::vk
