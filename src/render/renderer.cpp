#include "render/renderer.h"

#include "vulkan/device.h"
#include "vulkan/device_buffer.h"
#include "vulkan/vk_error.h"

#include <hmsm/vulkan.h>

// Generated at build time by cmake/HmsmRender.cmake (glslangValidator --vn).
#include "hmsm_spirv/render/backdrop_frag.h"
#include "hmsm_spirv/render/backdrop_vert.h"
#include "hmsm_spirv/render/mesh_frag.h"
#include "hmsm_spirv/render/mesh_vert.h"

#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <span>

namespace hmsm::render {

using detail::vk::Buffer;
using detail::vk::Device;
using detail::vk::MemoryUse;

namespace {

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
};
constexpr int32_t kModeBark = 0, kModeLeaf = 1, kModeShadowBark = 2, kModeShadowLeaf = 3;
constexpr int32_t kFlagAlphaToCoverage = 1;
constexpr int32_t kFlagPackedNormals = 2;  // normals decoded from the positions' w (mesh.vert)

constexpr VkFormat kColourFormat = VK_FORMAT_R8G8B8A8_SRGB;

void copy_matrix(const glm::dmat4& m, float out[16]) {
    const glm::mat4 f(m);
    std::memcpy(out, glm::value_ptr(f), sizeof(float) * 16);
}

int find_memory_type(const VkPhysicalDeviceMemoryProperties& memory, uint32_t bits,
                     VkMemoryPropertyFlags wanted) {
    for (uint32_t i = 0; i < memory.memoryTypeCount; ++i)
        if ((bits & (1u << i)) && (memory.memoryTypes[i].propertyFlags & wanted) == wanted) return int(i);
    return -1;
}

/// An image with its own memory and one view.
struct Image2D {
    VkImage image = VK_NULL_HANDLE;
    VkDeviceMemory memory = VK_NULL_HANDLE;
    VkImageView view = VK_NULL_HANDLE;
};

}  // namespace

const char* to_string(VertexSource source) {
    return source == VertexSource::device_buffers ? "device buffers (no readback)"
                                                  : "host upload (readback each frame)";
}

Status validate(const RenderSettings& s) {
    if (s.width < 16 || s.height < 16 || s.width > 8192 || s.height > 8192)
        return {ErrorCode::invalid_argument, "--width and --height must be within 16..8192 pixels"};
    if (s.msaa != 1 && s.msaa != 2 && s.msaa != 4 && s.msaa != 8)
        return {ErrorCode::invalid_argument, "--msaa " + std::to_string(s.msaa) + ": expected 1, 2, 4 or 8"};
    const CameraSettings& c = s.camera;
    if (c.distance && !(std::isfinite(*c.distance) && *c.distance > 0.0))
        return {ErrorCode::invalid_argument, "--camera-distance must be a finite number > 0"};
    if (!std::isfinite(c.yaw_degrees))
        return {ErrorCode::invalid_argument, "--camera-yaw must be finite"};
    if (c.pitch_degrees && !(std::isfinite(*c.pitch_degrees) && std::abs(*c.pitch_degrees) <= 89.0))
        return {ErrorCode::invalid_argument, "--camera-pitch must be within -89..89 degrees"};
    if (!(std::isfinite(c.fov_degrees) && c.fov_degrees >= 5.0 && c.fov_degrees <= 120.0))
        return {ErrorCode::invalid_argument, "--fov must be within 5..120 degrees"};
    if (!(std::isfinite(s.leaf_scale) && (s.leaf_scale == 0.0 || (s.leaf_scale >= 0.1 && s.leaf_scale <= 20.0))))
        return {ErrorCode::invalid_argument, "--leaf-scale must be auto or within 0.1..20"};
    return {};
}

// --- the renderer's Vulkan objects ---------------------------------------------------------

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

    Image2D colour_msaa, colour, depth;
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

    ~State();
    const VolkDeviceTable& vk() const { return device->vk(); }
    VkDevice dev() const { return device->handle(); }

    Status create_image(Image2D& out, VkFormat format, VkSampleCountFlagBits count,
                        VkImageUsageFlags usage, VkImageAspectFlags aspect, const char* name);
    void destroy_image(Image2D& image);
    Status choose_formats();
    Status create_targets();
    Status create_render_pass();
    Status create_descriptors();
    Status create_pipelines();
    Status create_geometry();
    Status create_commands();
    Status frame_scene();
    Status upload_vertices();
    void record_draws(VkCommandBuffer cmd);
};

Renderer::State::~State() {
    // After a frame timed out the device will not go idle: leave its objects to the driver
    // rather than wait forever.
    if (!device || device_hung) return;
    const VolkDeviceTable& t = vk();
    VkDevice d = dev();
    t.vkDeviceWaitIdle(d);
    if (fence) t.vkDestroyFence(d, fence, nullptr);
    if (command_pool) t.vkDestroyCommandPool(d, command_pool, nullptr);
    for (VkPipeline p : {backdrop, shadow, bark, leaf})
        if (p) t.vkDestroyPipeline(d, p, nullptr);
    for (VkShaderModule m : modules)
        if (m) t.vkDestroyShaderModule(d, m, nullptr);
    if (pipeline_layout) t.vkDestroyPipelineLayout(d, pipeline_layout, nullptr);
    if (descriptor_pool) t.vkDestroyDescriptorPool(d, descriptor_pool, nullptr);
    if (set_layout) t.vkDestroyDescriptorSetLayout(d, set_layout, nullptr);
    if (framebuffer) t.vkDestroyFramebuffer(d, framebuffer, nullptr);
    if (render_pass) t.vkDestroyRenderPass(d, render_pass, nullptr);
    destroy_image(colour_msaa);
    destroy_image(colour);
    destroy_image(depth);
}

void Renderer::State::destroy_image(Image2D& image) {
    if (image.view) vk().vkDestroyImageView(dev(), image.view, nullptr);
    if (image.image) vk().vkDestroyImage(dev(), image.image, nullptr);
    if (image.memory) vk().vkFreeMemory(dev(), image.memory, nullptr);
    image = {};
}

Status Renderer::State::create_image(Image2D& out, VkFormat format, VkSampleCountFlagBits count,
                                     VkImageUsageFlags usage, VkImageAspectFlags aspect,
                                     const char* name) {
    VkImageCreateInfo info{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
    info.imageType = VK_IMAGE_TYPE_2D;
    info.format = format;
    info.extent = {settings.width, settings.height, 1};
    info.mipLevels = 1;
    info.arrayLayers = 1;
    info.samples = count;
    info.tiling = VK_IMAGE_TILING_OPTIMAL;
    info.usage = usage;
    info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    info.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    HMSM_VK_TRY(vk().vkCreateImage(dev(), &info, nullptr, &out.image));
    VkMemoryRequirements requirements;
    vk().vkGetImageMemoryRequirements(dev(), out.image, &requirements);
    int type = find_memory_type(device->memory_properties(), requirements.memoryTypeBits,
                                VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
    if (type < 0) type = find_memory_type(device->memory_properties(), requirements.memoryTypeBits, 0);
    if (type < 0)
        return {ErrorCode::device_error, std::string("render: no memory type for the ") + name + " image"};
    VkMemoryAllocateInfo allocate{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    allocate.allocationSize = requirements.size;
    allocate.memoryTypeIndex = uint32_t(type);
    HMSM_VK_TRY(vk().vkAllocateMemory(dev(), &allocate, nullptr, &out.memory));
    HMSM_VK_TRY(vk().vkBindImageMemory(dev(), out.image, out.memory, 0));
    VkImageViewCreateInfo view{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    view.image = out.image;
    view.viewType = VK_IMAGE_VIEW_TYPE_2D;
    view.format = format;
    view.subresourceRange = {aspect, 0, 1, 0, 1};
    HMSM_VK_TRY(vk().vkCreateImageView(dev(), &view, nullptr, &out.view));
    return {};
}

Status Renderer::State::choose_formats() {
    VkPhysicalDeviceProperties properties;
    vkGetPhysicalDeviceProperties(device->physical_device(), &properties);
    auto supports = [&](VkFormat format, VkFormatFeatureFlags features) {
        VkFormatProperties p;
        vkGetPhysicalDeviceFormatProperties(device->physical_device(), format, &p);
        return (p.optimalTilingFeatures & features) == features;
    };
    if (!supports(kColourFormat, VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BIT |
                                     VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BLEND_BIT |
                                     VK_FORMAT_FEATURE_TRANSFER_SRC_BIT))
        return {ErrorCode::unsupported, "render: " + device->name() +
                                            " cannot render to R8G8B8A8_SRGB images"};
    // A stencil aspect lets each pixel be shadowed once; without one, no shadows.
    for (VkFormat f : {VK_FORMAT_D32_SFLOAT_S8_UINT, VK_FORMAT_D24_UNORM_S8_UINT}) {
        if (supports(f, VK_FORMAT_FEATURE_DEPTH_STENCIL_ATTACHMENT_BIT)) {
            depth_format = f;
            break;
        }
    }
    shadows = settings.shadows && depth_format != VK_FORMAT_UNDEFINED;
    if (depth_format == VK_FORMAT_UNDEFINED) depth_format = VK_FORMAT_D32_SFLOAT;
    if (!supports(depth_format, VK_FORMAT_FEATURE_DEPTH_STENCIL_ATTACHMENT_BIT))
        return {ErrorCode::unsupported, "render: " + device->name() + " has no depth format"};
    const VkSampleCountFlags counts = properties.limits.framebufferColorSampleCounts &
                                      properties.limits.framebufferDepthSampleCounts &
                                      properties.limits.framebufferStencilSampleCounts;
    samples = VK_SAMPLE_COUNT_1_BIT;
    for (uint32_t s = settings.msaa; s > 1; s /= 2)
        if (counts & s) {
            samples = VkSampleCountFlagBits(s);
            break;
        }
    return {};
}

Status Renderer::State::create_targets() {
    const bool msaa = samples != VK_SAMPLE_COUNT_1_BIT;
    if (msaa)
        HMSM_TRY(create_image(colour_msaa, kColourFormat, samples,
                              VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSIENT_ATTACHMENT_BIT,
                              VK_IMAGE_ASPECT_COLOR_BIT, "multisampled colour"));
    HMSM_TRY(create_image(colour, kColourFormat, VK_SAMPLE_COUNT_1_BIT,
                          VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
                          VK_IMAGE_ASPECT_COLOR_BIT, "colour"));
    const VkImageAspectFlags depth_aspect =
        VK_IMAGE_ASPECT_DEPTH_BIT |
        (depth_format == VK_FORMAT_D32_SFLOAT ? 0 : VK_IMAGE_ASPECT_STENCIL_BIT);
    HMSM_TRY(create_image(depth, depth_format, samples,
                          VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSIENT_ATTACHMENT_BIT,
                          depth_aspect, "depth"));
    auto readback_buffer = Buffer::create(*device, VkDeviceSize(settings.width) * settings.height * 4,
                                          VK_BUFFER_USAGE_TRANSFER_DST_BIT, MemoryUse::staging,
                                          "render readback");
    if (!readback_buffer) return readback_buffer.status();
    readback = std::move(readback_buffer).value();
    return {};
}

Status Renderer::State::create_render_pass() {
    const bool msaa = samples != VK_SAMPLE_COUNT_1_BIT;
    std::vector<VkAttachmentDescription> attachments;
    VkAttachmentDescription colour_attachment{};
    colour_attachment.format = kColourFormat;
    colour_attachment.samples = samples;
    colour_attachment.loadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;  // the backdrop covers every pixel
    colour_attachment.storeOp = msaa ? VK_ATTACHMENT_STORE_OP_DONT_CARE : VK_ATTACHMENT_STORE_OP_STORE;
    colour_attachment.stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
    colour_attachment.stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
    colour_attachment.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    colour_attachment.finalLayout =
        msaa ? VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL : VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
    attachments.push_back(colour_attachment);
    VkAttachmentDescription depth_attachment{};
    depth_attachment.format = depth_format;
    depth_attachment.samples = samples;
    depth_attachment.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
    depth_attachment.storeOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
    depth_attachment.stencilLoadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
    depth_attachment.stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
    depth_attachment.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    depth_attachment.finalLayout = VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL;
    attachments.push_back(depth_attachment);
    if (msaa) {
        VkAttachmentDescription resolve = colour_attachment;
        resolve.samples = VK_SAMPLE_COUNT_1_BIT;
        resolve.loadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
        resolve.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
        resolve.finalLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
        attachments.push_back(resolve);
    }
    VkAttachmentReference colour_ref{0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
    VkAttachmentReference depth_ref{1, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};
    VkAttachmentReference resolve_ref{2, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
    VkSubpassDescription subpass{};
    subpass.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
    subpass.colorAttachmentCount = 1;
    subpass.pColorAttachments = &colour_ref;
    subpass.pResolveAttachments = msaa ? &resolve_ref : nullptr;
    subpass.pDepthStencilAttachment = &depth_ref;
    // Before: the previous frame's copy out of the colour image and its depth tests are done.
    // After: the copy to the readback buffer waits for the (resolved) colour writes.
    VkSubpassDependency dependencies[2] = {};
    dependencies[0].srcSubpass = VK_SUBPASS_EXTERNAL;
    dependencies[0].dstSubpass = 0;
    dependencies[0].srcStageMask = VK_PIPELINE_STAGE_TRANSFER_BIT |
                                   VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT |
                                   VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT |
                                   VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT;
    dependencies[0].dstStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT |
                                   VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT |
                                   VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT;
    dependencies[0].srcAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT |
                                    VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT;
    dependencies[0].dstAccessMask = VK_ACCESS_COLOR_ATTACHMENT_READ_BIT | VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT |
                                    VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_READ_BIT |
                                    VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT;
    dependencies[1].srcSubpass = 0;
    dependencies[1].dstSubpass = VK_SUBPASS_EXTERNAL;
    dependencies[1].srcStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
    dependencies[1].dstStageMask = VK_PIPELINE_STAGE_TRANSFER_BIT;
    dependencies[1].srcAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
    dependencies[1].dstAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
    VkRenderPassCreateInfo info{VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO};
    info.attachmentCount = uint32_t(attachments.size());
    info.pAttachments = attachments.data();
    info.subpassCount = 1;
    info.pSubpasses = &subpass;
    info.dependencyCount = 2;
    info.pDependencies = dependencies;
    HMSM_VK_TRY(vk().vkCreateRenderPass(dev(), &info, nullptr, &render_pass));

    std::vector<VkImageView> views = {msaa ? colour_msaa.view : colour.view, depth.view};
    if (msaa) views.push_back(colour.view);
    VkFramebufferCreateInfo fb{VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO};
    fb.renderPass = render_pass;
    fb.attachmentCount = uint32_t(views.size());
    fb.pAttachments = views.data();
    fb.width = settings.width;
    fb.height = settings.height;
    fb.layers = 1;
    HMSM_VK_TRY(vk().vkCreateFramebuffer(dev(), &fb, nullptr, &framebuffer));
    return {};
}

Status Renderer::State::create_descriptors() {
    auto buffer = Buffer::create(*device, sizeof(FrameUniforms), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT,
                                 MemoryUse::staging, "render uniforms");
    if (!buffer) return buffer.status();
    uniforms = std::move(buffer).value();

    // 0: the frame constants; 1: the vertex positions again, as a storage buffer (leaf scale).
    VkDescriptorSetLayoutBinding bindings[2] = {};
    bindings[0].binding = 0;
    bindings[0].descriptorType = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
    bindings[0].descriptorCount = 1;
    bindings[0].stageFlags = VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT;
    bindings[1].binding = 1;
    bindings[1].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    bindings[1].descriptorCount = 1;
    bindings[1].stageFlags = VK_SHADER_STAGE_VERTEX_BIT;
    VkDescriptorSetLayoutCreateInfo layout{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
    layout.bindingCount = 2;
    layout.pBindings = bindings;
    HMSM_VK_TRY(vk().vkCreateDescriptorSetLayout(dev(), &layout, nullptr, &set_layout));

    VkDescriptorPoolSize sizes[2] = {{VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 1},
                                     {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1}};
    VkDescriptorPoolCreateInfo pool{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
    pool.maxSets = 1;
    pool.poolSizeCount = 2;
    pool.pPoolSizes = sizes;
    HMSM_VK_TRY(vk().vkCreateDescriptorPool(dev(), &pool, nullptr, &descriptor_pool));
    VkDescriptorSetAllocateInfo allocate{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
    allocate.descriptorPool = descriptor_pool;
    allocate.descriptorSetCount = 1;
    allocate.pSetLayouts = &set_layout;
    HMSM_VK_TRY(vk().vkAllocateDescriptorSets(dev(), &allocate, &descriptor_set));
    // The storage binding (1) is written by create_geometry() once the vertex buffers exist.
    VkDescriptorBufferInfo info{uniforms.handle(), 0, sizeof(FrameUniforms)};
    VkWriteDescriptorSet write{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    write.dstSet = descriptor_set;
    write.dstBinding = 0;
    write.descriptorCount = 1;
    write.descriptorType = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
    write.pBufferInfo = &info;
    vk().vkUpdateDescriptorSets(dev(), 1, &write, 0, nullptr);

    VkPushConstantRange push{VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0,
                             sizeof(DrawConstants)};
    VkPipelineLayoutCreateInfo pipeline{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
    pipeline.setLayoutCount = 1;
    pipeline.pSetLayouts = &set_layout;
    pipeline.pushConstantRangeCount = 1;
    pipeline.pPushConstantRanges = &push;
    HMSM_VK_TRY(vk().vkCreatePipelineLayout(dev(), &pipeline, nullptr, &pipeline_layout));
    return {};
}

Status Renderer::State::create_pipelines() {
    const std::span<const uint32_t> code[4] = {hmsm_spirv_render_backdrop_vert, hmsm_spirv_render_backdrop_frag,
                                               hmsm_spirv_render_mesh_vert, hmsm_spirv_render_mesh_frag};
    for (int i = 0; i < 4; ++i) {
        VkShaderModuleCreateInfo info{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
        info.codeSize = code[i].size_bytes();
        info.pCode = code[i].data();
        HMSM_VK_TRY(vk().vkCreateShaderModule(dev(), &info, nullptr, &modules[i]));
    }
    enum class Kind { backdrop, shadow, bark, leaf };
    auto make = [&](Kind kind, VkPipeline& out) -> Status {
        const bool mesh = kind != Kind::backdrop;
        VkPipelineShaderStageCreateInfo stages[2] = {{VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO},
                                                     {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO}};
        stages[0].stage = VK_SHADER_STAGE_VERTEX_BIT;
        stages[0].module = modules[mesh ? 2 : 0];
        stages[0].pName = "main";
        stages[1].stage = VK_SHADER_STAGE_FRAGMENT_BIT;
        stages[1].module = modules[mesh ? 3 : 1];
        stages[1].pName = "main";

        // Positions and normals: the simulation's vec4 buffers, one binding each.
        VkVertexInputBindingDescription bindings[2] = {{0, 16, VK_VERTEX_INPUT_RATE_VERTEX},
                                                       {1, 16, VK_VERTEX_INPUT_RATE_VERTEX}};
        VkVertexInputAttributeDescription attributes[2] = {{0, 0, VK_FORMAT_R32G32B32A32_SFLOAT, 0},
                                                           {1, 1, VK_FORMAT_R32G32B32A32_SFLOAT, 0}};
        VkPipelineVertexInputStateCreateInfo input{VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO};
        if (mesh) {
            input.vertexBindingDescriptionCount = 2;
            input.pVertexBindingDescriptions = bindings;
            input.vertexAttributeDescriptionCount = 2;
            input.pVertexAttributeDescriptions = attributes;
        }
        VkPipelineInputAssemblyStateCreateInfo assembly{VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO};
        assembly.topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST;
        VkViewport viewport{0.0f, 0.0f, float(settings.width), float(settings.height), 0.0f, 1.0f};
        VkRect2D scissor{{0, 0}, {settings.width, settings.height}};
        VkPipelineViewportStateCreateInfo viewport_state{VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO};
        viewport_state.viewportCount = 1;
        viewport_state.pViewports = &viewport;
        viewport_state.scissorCount = 1;
        viewport_state.pScissors = &scissor;
        VkPipelineRasterizationStateCreateInfo raster{VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO};
        raster.polygonMode = VK_POLYGON_MODE_FILL;
        // The mesh is counter-clockwise seen from outside; the projection flips y, which turns
        // that into clockwise in framebuffer coordinates.
        raster.cullMode = kind == Kind::bark ? VK_CULL_MODE_BACK_BIT : VK_CULL_MODE_NONE;
        raster.frontFace = VK_FRONT_FACE_CLOCKWISE;
        raster.lineWidth = 1.0f;
        VkPipelineMultisampleStateCreateInfo multisample{VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO};
        multisample.rasterizationSamples = samples;
        multisample.alphaToCoverageEnable = kind == Kind::leaf && samples != VK_SAMPLE_COUNT_1_BIT;
        VkPipelineDepthStencilStateCreateInfo depth_state{VK_STRUCTURE_TYPE_PIPELINE_DEPTH_STENCIL_STATE_CREATE_INFO};
        depth_state.depthTestEnable = VK_TRUE;
        depth_state.depthWriteEnable = kind == Kind::shadow ? VK_FALSE : VK_TRUE;
        depth_state.depthCompareOp = kind == Kind::backdrop ? VK_COMPARE_OP_ALWAYS
                                     : kind == Kind::shadow ? VK_COMPARE_OP_LESS_OR_EQUAL
                                                            : VK_COMPARE_OP_LESS;
        if (kind == Kind::shadow) {
            // Darken each sample once however many shadow triangles cover it.
            depth_state.stencilTestEnable = VK_TRUE;
            VkStencilOpState op{VK_STENCIL_OP_KEEP, VK_STENCIL_OP_INCREMENT_AND_CLAMP, VK_STENCIL_OP_KEEP,
                                VK_COMPARE_OP_EQUAL, 0xff, 0xff, 0};
            depth_state.front = op;
            depth_state.back = op;
        }
        VkPipelineColorBlendAttachmentState blend{};
        blend.colorWriteMask = VK_COLOR_COMPONENT_R_BIT | VK_COLOR_COMPONENT_G_BIT |
                               VK_COLOR_COMPONENT_B_BIT | VK_COLOR_COMPONENT_A_BIT;
        if (kind == Kind::shadow) {
            blend.blendEnable = VK_TRUE;
            blend.srcColorBlendFactor = VK_BLEND_FACTOR_ZERO;
            blend.dstColorBlendFactor = VK_BLEND_FACTOR_ONE_MINUS_SRC_ALPHA;
            blend.colorBlendOp = VK_BLEND_OP_ADD;
            blend.srcAlphaBlendFactor = VK_BLEND_FACTOR_ZERO;
            blend.dstAlphaBlendFactor = VK_BLEND_FACTOR_ONE;
            blend.alphaBlendOp = VK_BLEND_OP_ADD;
        }
        VkPipelineColorBlendStateCreateInfo blend_state{VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO};
        blend_state.attachmentCount = 1;
        blend_state.pAttachments = &blend;
        VkGraphicsPipelineCreateInfo info{VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO};
        info.stageCount = 2;
        info.pStages = stages;
        info.pVertexInputState = &input;
        info.pInputAssemblyState = &assembly;
        info.pViewportState = &viewport_state;
        info.pRasterizationState = &raster;
        info.pMultisampleState = &multisample;
        info.pDepthStencilState = &depth_state;
        info.pColorBlendState = &blend_state;
        info.layout = pipeline_layout;
        info.renderPass = render_pass;
        info.subpass = 0;
        HMSM_VK_TRY(vk().vkCreateGraphicsPipelines(dev(), VK_NULL_HANDLE, 1, &info, nullptr, &out));
        return {};
    };
    HMSM_TRY(make(Kind::backdrop, backdrop));
    if (shadows) HMSM_TRY(make(Kind::shadow, shadow));
    HMSM_TRY(make(Kind::bark, bark));
    HMSM_TRY(make(Kind::leaf, leaf));
    return {};
}

Status Renderer::State::create_geometry() {
    const Scene& scene = simulation->scene();
    std::vector<uint32_t> all_indices;
    models.resize(scene.models.size());
    for (uint32_t m = 0; m < scene.models.size(); ++m) {
        const MeshTemplate& mesh = simulation->mesh(m);
        ModelDraw& draw = models[m];
        draw.first_index = uint32_t(all_indices.size());
        draw.leaf_indices = 6 * mesh.leaf_count;  // leaf cards come last (src/mesh.cpp)
        draw.bark_indices = uint32_t(mesh.indices.size()) - draw.leaf_indices;
        draw.vertices = uint32_t(mesh.vertices.size());
        draw.leaf_vertices = 4 * mesh.leaf_count;
        all_indices.insert(all_indices.end(), mesh.indices.begin(), mesh.indices.end());
    }
    int64_t first_vertex = 0;
    for (const Instance& instance : scene.instances) {
        instances.emplace_back(instance.model, first_vertex);
        first_vertex += models[instance.model].vertices;
    }
    if (uint64_t(first_vertex) != simulation->vertex_count())
        return {ErrorCode::internal, "render: mesh vertex counts do not add up to the simulation's"};
    if (first_vertex > std::numeric_limits<int32_t>::max())
        return {ErrorCode::unsupported, "render: more than 2^31 mesh vertices in one scene"};

    auto index_buffer = Buffer::create(*device, std::max<VkDeviceSize>(4, all_indices.size() * 4),
                                       VK_BUFFER_USAGE_INDEX_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                                       MemoryUse::device_local, "render indices");
    if (!index_buffer) return index_buffer.status();
    indices = std::move(index_buffer).value();
    auto transfer = detail::vk::Transfer::create(*device);
    if (!transfer) return transfer.status();
    HMSM_TRY(transfer.value()->upload(indices, 0, all_indices.size() * 4,
                                      [&](void* dst, VkDeviceSize first, VkDeviceSize bytes) {
                                          std::memcpy(dst, reinterpret_cast<const uint8_t*>(all_indices.data()) + first, bytes);
                                      }));

    if (simulation->backend_kind() == BackendKind::vulkan) {
        auto handles = hmsm::vulkan::device_handles(*simulation);
        if (!handles) return handles.status();
        if (handles->device != device->handle())
            return {ErrorCode::internal, "render: the Vulkan simulation runs on another device"};
        auto shared = hmsm::vulkan::shared_buffers(*simulation);
        if (!shared) return shared.status();
        source = VertexSource::device_buffers;
        positions = shared->vertex_positions.buffer;
        positions_offset = shared->vertex_positions.offset;
        packed_normals = shared->vertex_layout == VertexLayout::packed;
        const hmsm::vulkan::BufferRange& normal_range = packed_normals ? shared->vertex_positions : shared->vertex_normals;
        normals = normal_range.buffer;
        normals_offset = normal_range.offset;
        positions_size = shared->vertex_positions.size;
        if (shared->vertex_positions.stride != 16 || normal_range.stride != 16)
            return {ErrorCode::internal, "render: the simulation's vertex buffers are not vec4"};
    } else {
        source = VertexSource::host_upload;
        const VkDeviceSize bytes = std::max<VkDeviceSize>(16, VkDeviceSize(first_vertex) * 16);
        auto p = Buffer::create(*device, bytes,
                                VK_BUFFER_USAGE_VERTEX_BUFFER_BIT | VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                                MemoryUse::staging, "render positions");
        if (!p) return p.status();
        auto n = Buffer::create(*device, bytes, VK_BUFFER_USAGE_VERTEX_BUFFER_BIT, MemoryUse::staging,
                                "render normals");
        if (!n) return n.status();
        upload_positions = std::move(p).value();
        upload_normals = std::move(n).value();
        positions = upload_positions.handle();
        normals = upload_normals.handle();
        positions_size = bytes;
    }
    // Scaling leaves reads positions as a storage buffer; past the device's storage range it is
    // left at 1 (docs/render.md).
    leaf_scale = settings.leaf_scale;
    VkDeviceSize range = std::max<VkDeviceSize>(16, positions_size);
    if (range > device->limits().max_storage_buffer_range) {
        range = device->limits().max_storage_buffer_range / 16 * 16;
        leaf_scale = 1.0;
    }
    VkDescriptorBufferInfo info{positions, positions_offset, range};
    VkWriteDescriptorSet write{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    write.dstSet = descriptor_set;
    write.dstBinding = 1;
    write.descriptorCount = 1;
    write.descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    write.pBufferInfo = &info;
    vk().vkUpdateDescriptorSets(dev(), 1, &write, 0, nullptr);
    return {};
}

Status Renderer::State::create_commands() {
    VkCommandPoolCreateInfo pool{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pool.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    pool.queueFamilyIndex = device->queue_family();
    HMSM_VK_TRY(vk().vkCreateCommandPool(dev(), &pool, nullptr, &command_pool));
    VkCommandBufferAllocateInfo allocate{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    allocate.commandPool = command_pool;
    allocate.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    allocate.commandBufferCount = 1;
    HMSM_VK_TRY(vk().vkAllocateCommandBuffers(dev(), &allocate, &command_buffer));
    VkFenceCreateInfo fence_info{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    HMSM_VK_TRY(vk().vkCreateFence(dev(), &fence_info, nullptr, &fence));
    return {};
}

// Frames the camera on the current pose (padded for sway) and fills the uniform buffer.
Status Renderer::State::frame_scene() {
    std::vector<float> xyz;
    HMSM_TRY(simulation->read(Output::vertex_positions, xyz));
    Bounds bounds;
    bounds.min = glm::dvec3(std::numeric_limits<double>::infinity());
    bounds.max = -bounds.min;
    for (size_t i = 0; i + 2 < xyz.size(); i += 3) {
        const glm::dvec3 p(xyz[i], xyz[i + 1], xyz[i + 2]);
        bounds.min = glm::min(bounds.min, p);
        bounds.max = glm::max(bounds.max, p);
    }
    double ground = std::numeric_limits<double>::infinity();
    for (const Instance& instance : simulation->scene().instances) ground = std::min(ground, instance.origin.y);
    if (bounds.empty()) bounds.min = bounds.max = glm::dvec3(0.0);
    if (!std::isfinite(ground)) ground = bounds.min.y;
    // Include the ground under the trees and leave room for the crown to sway sideways.
    bounds.min.y = std::min(bounds.min.y, ground);
    const double height = std::max(bounds.max.y - bounds.min.y, 1e-3);
    bounds.min.x -= 0.08 * height;
    bounds.max.x += 0.08 * height;
    bounds.min.z -= 0.08 * height;
    bounds.max.z += 0.08 * height;

    const bool forest = simulation->scene().instances.size() > 1;
    const double aspect = double(settings.width) / double(settings.height);
    camera = frame_camera(bounds, settings.camera, aspect, forest);

    // The sun stands behind the camera's left shoulder, whatever the camera's yaw.
    const double yaw = glm::radians(settings.camera.yaw_degrees);
    const glm::dvec3 sun_camera = glm::normalize(glm::dvec3(-0.55, 0.75, 0.45));
    const glm::dvec3 sun(std::cos(yaw) * sun_camera.x + std::sin(yaw) * sun_camera.z, sun_camera.y,
                         -std::sin(yaw) * sun_camera.x + std::cos(yaw) * sun_camera.z);
    const double distance = glm::length(camera.eye - camera.target);
    const double radius = 0.5 * glm::length(bounds.max - bounds.min);
    if (leaf_scale == 0.0) {
        // Auto: the mean leaf side against the height of the view at the target.
        double sum = 0.0;
        size_t count = 0;
        for (const TreeModel& model : simulation->scene().models)
            for (const TreeLeaf& leaf : model.leaves) {
                sum += std::sqrt(std::abs(leaf.size.x * leaf.size.y));
                ++count;
            }
        const double view_height = 2.0 * distance * std::tan(0.5 * glm::radians(camera.fov_degrees));
        leaf_scale = count && sum > 0.0
                         ? std::clamp(0.011 * view_height / (sum / double(count)), 1.0, 6.0)
                         : 1.0;
    }

    FrameUniforms u{};
    const glm::dmat4 view_proj = camera.view_projection();
    copy_matrix(view_proj, u.view_proj);
    copy_matrix(glm::inverse(view_proj), u.inv_view_proj);
    u.eye[0] = float(camera.eye.x), u.eye[1] = float(camera.eye.y), u.eye[2] = float(camera.eye.z);
    u.sun[0] = float(sun.x), u.sun[1] = float(sun.y), u.sun[2] = float(sun.z);
    u.ground[0] = float(ground);
    u.ground[1] = float(2e-3 * distance);
    u.ground[2] = float(1.5 * (distance + radius));
    u.ground[3] = float(15.0 * (distance + radius));
    // Checker squares of a power of two metres, about a tenth of the tree's height.
    u.scale[0] = float(std::exp2(std::round(std::log2(std::max(height, 1e-3) / 10.0))));
    u.scale[1] = float(leaf_scale);
    std::memcpy(uniforms.mapped(), &u, sizeof u);
    return {};
}

Status Renderer::State::upload_vertices() {
    const uint64_t count = simulation->vertex_count();
    for (auto [output, buffer, w] : {std::tuple{Output::vertex_positions, &upload_positions, 1.0f},
                                     std::tuple{Output::vertex_normals, &upload_normals, 0.0f}}) {
        HMSM_TRY(simulation->read(output, host_xyz));
        if (host_xyz.size() != 3 * count)
            return {ErrorCode::internal, "render: unexpected vertex output size"};
        auto* dst = static_cast<float*>(buffer->mapped());
        for (uint64_t v = 0; v < count; ++v) {
            dst[4 * v] = host_xyz[3 * v];
            dst[4 * v + 1] = host_xyz[3 * v + 1];
            dst[4 * v + 2] = host_xyz[3 * v + 2];
            dst[4 * v + 3] = w;
        }
    }
    return {};
}

void Renderer::State::record_draws(VkCommandBuffer cmd) {
    const VolkDeviceTable& t = vk();
    t.vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline_layout, 0, 1,
                              &descriptor_set, 0, nullptr);
    t.vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, backdrop);
    t.vkCmdDraw(cmd, 3, 1, 0, 0);
    if (!settings.draw_trees || instances.empty()) return;

    VkBuffer buffers[2] = {positions, normals};
    VkDeviceSize offsets[2] = {positions_offset, normals_offset};
    t.vkCmdBindVertexBuffers(cmd, 0, 2, buffers, offsets);
    t.vkCmdBindIndexBuffer(cmd, indices.handle(), 0, VK_INDEX_TYPE_UINT32);
    const int32_t flags = (samples != VK_SAMPLE_COUNT_1_BIT ? kFlagAlphaToCoverage : 0) |
                          (packed_normals ? kFlagPackedNormals : 0);
    auto draw_all = [&](int32_t bark_mode, int32_t leaf_mode) {
        for (size_t i = 0; i < instances.size(); ++i) {
            const ModelDraw& m = models[instances[i].first];
            const int32_t first_vertex = int32_t(instances[i].second);
            DrawConstants c{bark_mode, first_vertex + int32_t(m.vertices - m.leaf_vertices), int32_t(i), flags};
            if (bark_mode >= 0 && m.bark_indices) {
                t.vkCmdPushConstants(cmd, pipeline_layout, VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT,
                                     0, sizeof c, &c);
                t.vkCmdDrawIndexed(cmd, m.bark_indices, 1, m.first_index, first_vertex, 0);
            }
            if (leaf_mode >= 0 && m.leaf_indices) {
                c.mode = leaf_mode;
                t.vkCmdPushConstants(cmd, pipeline_layout, VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT,
                                     0, sizeof c, &c);
                t.vkCmdDrawIndexed(cmd, m.leaf_indices, 1, m.first_index + m.bark_indices, first_vertex, 0);
            }
        }
    };
    if (shadows) {
        t.vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, shadow);
        draw_all(kModeShadowBark, kModeShadowLeaf);
    }
    t.vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, bark);
    draw_all(kModeBark, -1);
    t.vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, leaf);
    draw_all(-1, kModeLeaf);
}

// --- Renderer ------------------------------------------------------------------------------

Renderer::Renderer(std::unique_ptr<State> state) : state_(std::move(state)) {}
Renderer::~Renderer() = default;

VertexSource Renderer::vertex_source() const { return state_->source; }
const Camera& Renderer::camera() const { return state_->camera; }
uint32_t Renderer::samples() const { return uint32_t(state_->samples); }
bool Renderer::shadows() const { return state_->shadows; }
double Renderer::leaf_scale() const { return state_->leaf_scale; }

Result<std::unique_ptr<Renderer>> Renderer::create(std::shared_ptr<Device> device,
                                                   Simulation& simulation,
                                                   const RenderSettings& settings) {
    HMSM_TRY(validate(settings));
    if (!device) return Status{ErrorCode::internal, "render: no device"};
    // Graphics needs a queue family with graphics; hmsm's device has one queue, of the family
    // chosen for compute. On every driver we know (lavapipe, NVIDIA, AMD, Intel) that is the
    // universal family 0.
    uint32_t family_count = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(device->physical_device(), &family_count, nullptr);
    std::vector<VkQueueFamilyProperties> families(family_count);
    vkGetPhysicalDeviceQueueFamilyProperties(device->physical_device(), &family_count, families.data());
    if (device->queue_family() >= family_count ||
        !(families[device->queue_family()].queueFlags & VK_QUEUE_GRAPHICS_BIT))
        return Status{ErrorCode::unsupported, "render: the queue hmsm uses on " + device->name() +
                                                  " cannot draw (no graphics in its queue family)"};
    auto state = std::make_unique<State>();
    state->device = std::move(device);
    state->simulation = &simulation;
    state->settings = settings;
    HMSM_TRY(state->choose_formats());
    HMSM_TRY(state->create_targets());
    HMSM_TRY(state->create_render_pass());
    HMSM_TRY(state->create_descriptors());
    HMSM_TRY(state->create_pipelines());
    HMSM_TRY(state->create_geometry());
    HMSM_TRY(state->create_commands());
    HMSM_TRY(state->frame_scene());
    HMSM_TRY(state->device->take_validation_messages());
    return std::unique_ptr<Renderer>(new Renderer(std::move(state)));
}

Status Renderer::render(uint32_t steps, Image& image) {
    State& s = *state_;
    const VolkDeviceTable& t = s.vk();
    if (s.source == VertexSource::host_upload) {
        if (steps) HMSM_TRY(s.simulation->step(steps));
        HMSM_TRY(s.upload_vertices());
    }
    VkCommandBuffer cmd = s.command_buffer;
    HMSM_VK_TRY(t.vkResetCommandBuffer(cmd, 0));
    VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    HMSM_VK_TRY(t.vkBeginCommandBuffer(cmd, &begin));
    if (s.source == VertexSource::device_buffers) {
        // The previous frame's vertex fetches finish before the steps overwrite the buffers...
        VkMemoryBarrier before{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
        before.srcAccessMask = VK_ACCESS_VERTEX_ATTRIBUTE_READ_BIT | VK_ACCESS_SHADER_READ_BIT;
        before.dstAccessMask = VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_SHADER_READ_BIT;
        t.vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_VERTEX_INPUT_BIT | VK_PIPELINE_STAGE_VERTEX_SHADER_BIT,
                               VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                               0, 1, &before, 0, nullptr, 0, nullptr);
        if (steps) {
            Status recorded = hmsm::vulkan::record_steps(*s.simulation, cmd, steps);
            if (!recorded) {
                t.vkEndCommandBuffer(cmd);
                return recorded;
            }
        }
        // ...and the vertex fetches of this frame see what the steps (or earlier work) wrote.
        VkMemoryBarrier after{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
        after.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
        after.dstAccessMask = VK_ACCESS_VERTEX_ATTRIBUTE_READ_BIT | VK_ACCESS_SHADER_READ_BIT;
        t.vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                               VK_PIPELINE_STAGE_VERTEX_INPUT_BIT | VK_PIPELINE_STAGE_VERTEX_SHADER_BIT,
                               0, 1, &after, 0, nullptr, 0, nullptr);
    }
    VkClearValue clears[3] = {};
    clears[1].depthStencil = {1.0f, 0};
    VkRenderPassBeginInfo pass{VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
    pass.renderPass = s.render_pass;
    pass.framebuffer = s.framebuffer;
    pass.renderArea = {{0, 0}, {s.settings.width, s.settings.height}};
    pass.clearValueCount = s.samples != VK_SAMPLE_COUNT_1_BIT ? 3 : 2;
    pass.pClearValues = clears;
    t.vkCmdBeginRenderPass(cmd, &pass, VK_SUBPASS_CONTENTS_INLINE);
    s.record_draws(cmd);
    t.vkCmdEndRenderPass(cmd);

    VkBufferImageCopy region{};
    region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    region.imageExtent = {s.settings.width, s.settings.height, 1};
    t.vkCmdCopyImageToBuffer(cmd, s.colour.image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                             s.readback.handle(), 1, &region);
    VkMemoryBarrier to_host{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    to_host.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    to_host.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
    t.vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1,
                           &to_host, 0, nullptr, 0, nullptr);
    HMSM_VK_TRY(t.vkEndCommandBuffer(cmd));

    VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    submit.commandBufferCount = 1;
    submit.pCommandBuffers = &cmd;
    HMSM_VK_TRY(t.vkQueueSubmit(s.device->queue(), 1, &submit, s.fence));
    // A frame that the device never finishes is reported, not waited for forever (seen on an
    // H100 with driver 580: graphics submissions there never signal their fence).
    constexpr uint64_t kFrameTimeoutNs = 30'000'000'000ull;
    VkResult waited = t.vkWaitForFences(s.dev(), 1, &s.fence, VK_TRUE, kFrameTimeoutNs);
    if (waited == VK_TIMEOUT) {
        s.device_hung = true;
        s.device->abandon();
        return Status{ErrorCode::device_error, "render: " + s.device->name() +
                                                   " did not finish drawing a frame within 30 s"};
    }
    HMSM_VK_TRY(waited);
    HMSM_VK_TRY(t.vkResetFences(s.dev(), 1, &s.fence));
    HMSM_TRY(s.device->take_validation_messages());

    image.width = s.settings.width;
    image.height = s.settings.height;
    image.rgba.resize(size_t(image.width) * image.height * 4);
    std::memcpy(image.rgba.data(), s.readback.mapped(), image.rgba.size());
    return {};
}

Result<std::unique_ptr<Session>> open_session(const Scene& scene, SimulationConfig config,
                                              const RenderSettings& settings) {
    HMSM_TRY(validate(settings));
    auto session = std::make_unique<Session>();
    auto device = Device::create();
    if (!device) return device.status();
    session->device = std::move(device).value();
    if (config.backend == BackendKind::automatic || config.backend == BackendKind::vulkan) {
        hmsm::vulkan::ExternalContext context;
        context.instance = session->device->instance();
        context.physical_device = session->device->physical_device();
        context.device = session->device->handle();
        context.queue = session->device->queue();
        context.queue_family_index = session->device->queue_family();
        auto simulation = hmsm::vulkan::create_simulation(scene, config, context);
        if (!simulation) return simulation.status();
        session->simulation = std::move(simulation).value();
    } else {
        auto simulation = Simulation::create(scene, config);
        if (!simulation) return simulation.status();
        session->simulation = std::move(simulation).value();
    }
    auto renderer = Renderer::create(session->device, *session->simulation, settings);
    if (!renderer) return renderer.status();
    session->renderer = std::move(renderer).value();
    return session;
}

}  // namespace hmsm::render
