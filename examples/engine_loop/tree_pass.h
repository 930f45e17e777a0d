// The engine's graphics pass of examples/engine_loop: draws a skinned tree in one colour into an
// offscreen image per frame in flight and copies the image to a host buffer.
#pragma once

#include "../common/engine_vulkan.h"

#include <array>
#include <memory>
#include <vector>

namespace engine {

/// Per vertex of the bind pose: position, two joints (model chain ids, -1 unused) and weights.
struct SkinnedVertex {
    float position[3];
    int32_t joints[2];
    float weights[2];
};

/// One frame slot's targets: colour image, framebuffer, the image copied to the host, and the
/// skinned positions the vertex shader writes out (vec4 per vertex).
struct FrameTargets {
    VkImage image = VK_NULL_HANDLE;
    VkDeviceMemory memory = VK_NULL_HANDLE;
    VkImageView view = VK_NULL_HANDLE;
    VkFramebuffer framebuffer = VK_NULL_HANDLE;
    VkDescriptorSet descriptors = VK_NULL_HANDLE;
    std::unique_ptr<HostBuffer> pixels;
    std::unique_ptr<HostBuffer> skinned;
};

class TreePass {
public:
    static constexpr uint32_t kWidth = 256, kHeight = 256;
    static constexpr std::array<uint8_t, 4> kBackground = {230, 238, 245, 255};

    /// `joints`: hmsm's joint-matrix buffer range (bound as it is, no copy); `inverse_binds`:
    /// 12 floats per model chain; `slots`: frames in flight.
    TreePass(const Device& device, const std::vector<SkinnedVertex>& vertices, const std::vector<uint32_t>& indices,
             const std::vector<float>& inverse_binds, VkBuffer joints, VkDeviceSize joints_offset,
             VkDeviceSize joints_size, uint32_t slots);
    ~TreePass();
    TreePass(const TreePass&) = delete;
    TreePass& operator=(const TreePass&) = delete;

    /// Records the draw into `cmd` (after hmsm's recorded steps) for frame slot `slot`: a
    /// barrier from hmsm's compute writes of the joint matrices to the vertex shader, the render
    /// pass, the copy of the image to the slot's host buffer, and the barriers that let the host
    /// read it and the next frame's compute overwrite the joints.
    void record(VkCommandBuffer cmd, uint32_t slot, const std::array<float, 16>& view_proj) const;

    /// RGBA8 pixels and skinned positions of the last frame recorded for `slot` (valid once its
    /// fence has signalled).
    const uint8_t* pixels(uint32_t slot) const { return targets_[slot].pixels->data<uint8_t>(); }
    const float* skinned(uint32_t slot) const { return targets_[slot].skinned->data<float>(); }

private:
    void create_render_pass();
    void create_pipeline();
    void create_targets(VkBuffer joints, VkDeviceSize joints_offset, VkDeviceSize joints_size);

    const Device& device_;
    uint32_t vertex_count_, index_count_;
    HostBuffer vertices_, indices_, inverse_binds_;
    VkRenderPass render_pass_ = VK_NULL_HANDLE;
    VkDescriptorSetLayout set_layout_ = VK_NULL_HANDLE;
    VkPipelineLayout layout_ = VK_NULL_HANDLE;
    VkPipeline pipeline_ = VK_NULL_HANDLE;
    VkDescriptorPool pool_ = VK_NULL_HANDLE;
    std::vector<FrameTargets> targets_;
};

}  // namespace engine
