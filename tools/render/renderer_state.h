// The renderer's Vulkan objects, shared by its parts (docs/render.md):
// - resources.cpp: targets, render pass, descriptors, pipelines, command buffer;
// - vertex_sources.cpp: index buffer, where the vertices come from, camera framing;
// - frame.cpp: recording the draws, submitting a frame and reading the picture back;
// - skinned.cpp: the bind-mesh and joint-matrix buffers of DrawMode::skinned;
// - renderer.cpp: settings validation, Renderer's construction and open_session.
#pragma once

#include "render/renderer.h"

#include "vulkan/device.h"
#include "vulkan/device_buffer.h"
#include "vulkan/vk_error.h"

#include <hmsm/skin.h>
#include <hmsm/vulkan.h>

#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

namespace hmsm::render {

using detail::vk::Buffer;
using detail::vk::Device;
using detail::vk::MemoryUse;

namespace internal {

// Mirrors shaders/glsl/render/render_common.glsl.
struct FrameUniforms {
    float view_proj[16];
    float inv_view_proj[16];
    float eye[4];
    float sun[4];
    float ground[4];  // height, shadow lift, fog start, fog end
    float scale[4];   // checker size, leaf-card scale
};
static_assert(sizeof(FrameUniforms) == 192, "std140 layout of Frame");

struct DrawConstants {
    int32_t mode;
    int32_t leaf_first;
    int32_t instance;
    int32_t flags;
    int32_t chain_base;  // skinned: the instance's first chain in the joint buffer
    int32_t bind_base;   // skinned: the model's first chain in the inverse-bind buffer
    int32_t pad[2];
};
constexpr int32_t kModeBark = 0, kModeLeaf = 1, kModeShadowBark = 2, kModeShadowLeaf = 3;
constexpr int32_t kFlagAlphaToCoverage = 1;
constexpr int32_t kFlagPackedNormals = 2;  // normals decoded from the positions' w (mesh.vert)

constexpr VkFormat kColourFormat = VK_FORMAT_R8G8B8A8_SRGB;

/// An image with its own memory and one view.
struct Image2D {
    VkImage image = VK_NULL_HANDLE;
    VkDeviceMemory memory = VK_NULL_HANDLE;
    VkImageView view = VK_NULL_HANDLE;
};

}  // namespace internal

struct Renderer::State {
    std::shared_ptr<Device> device;
    Simulation* simulation = nullptr;
    RenderSettings settings;
    VertexSource source = VertexSource::host_upload;
    Camera camera;
    VkSampleCountFlagBits samples = VK_SAMPLE_COUNT_1_BIT;
    VkFormat depth_format = VK_FORMAT_UNDEFINED;
    bool shadows = false;
    double leaf_scale = 1.0;

    internal::Image2D colour_msaa, colour, depth;
    VkRenderPass render_pass = VK_NULL_HANDLE;
    VkFramebuffer framebuffer = VK_NULL_HANDLE;
    VkDescriptorSetLayout set_layout = VK_NULL_HANDLE;
    VkDescriptorPool descriptor_pool = VK_NULL_HANDLE;
    VkDescriptorSet descriptor_set = VK_NULL_HANDLE;
    VkPipelineLayout pipeline_layout = VK_NULL_HANDLE;
    VkShaderModule modules[4] = {};
    VkPipeline backdrop = VK_NULL_HANDLE, shadow = VK_NULL_HANDLE, bark = VK_NULL_HANDLE,
               leaf = VK_NULL_HANDLE;
    VkCommandPool command_pool = VK_NULL_HANDLE;
    VkCommandBuffer command_buffer = VK_NULL_HANDLE;
    VkFence fence = VK_NULL_HANDLE;

    Buffer uniforms, readback, indices;
    bool device_hung = false;  // a frame never finished (see draw_frame)
    Buffer upload_positions, upload_normals;  // host_upload only
    VkBuffer positions = VK_NULL_HANDLE, normals = VK_NULL_HANDLE;
    VkDeviceSize positions_offset = 0, normals_offset = 0, positions_size = 0;
    // device_buffers of a VertexLayout::packed simulation: no normal buffer; the vertex shader
    // decodes each normal from its position's w, and the normal attribute is bound to the
    // positions (read, never used).
    bool packed_normals = false;

    // Per model: first index and counts; per instance: vertex base and model.
    struct ModelDraw {
        uint32_t first_index = 0, bark_indices = 0, leaf_indices = 0, vertices = 0, leaf_vertices = 0;
    };
    std::vector<ModelDraw> models;
    std::vector<std::pair<uint32_t, int64_t>> instances;  // (model, first vertex)

    std::vector<float> host_xyz;  // host_upload scratch

    // DrawMode::skinned (skinned.cpp): per model its skin; the bind vertices and inverse binds
    // of all models (storage bindings 2 and 3) and the joint palette (binding 4: the
    // simulation's own buffer, or upload_joints with host_upload).
    bool skinned = false;
    std::vector<SkinTemplate> skins;
    std::vector<int32_t> model_bind_base, instance_chain_base;
    Buffer skin_vertices, inverse_binds, upload_joint_buffer;
    VkBuffer joints = VK_NULL_HANDLE;
    VkDeviceSize joints_offset = 0, joints_size = 0;

    ~State();
    const VolkDeviceTable& vk() const { return device->vk(); }
    VkDevice dev() const { return device->handle(); }

    Status create_image(internal::Image2D& out, VkFormat format, VkSampleCountFlagBits count,
                        VkImageUsageFlags usage, VkImageAspectFlags aspect, const char* name);
    void destroy_image(internal::Image2D& image);
    Status choose_formats();
    Status create_targets();
    Status create_render_pass();
    Status create_descriptors();
    Status create_pipelines();
    Status create_geometry();
    Status create_commands();
    Status frame_scene();
    Status upload_vertices();
    Status create_skin_sources();  // skinned.cpp
    Status upload_joints();        // skinned.cpp
    Status skinned_positions(std::vector<float>& xyz);  // skinned.cpp: host skinning
    void record_draws(VkCommandBuffer cmd);
};

}  // namespace hmsm::render
