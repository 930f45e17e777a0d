#include "render/renderer_state.h"

// Generated at build time by cmake/HmsmRender.cmake (glslangValidator --vn).
#include "hmsm_spirv/render/backdrop_frag.h"
#include "hmsm_spirv/render/backdrop_vert.h"
#include "hmsm_spirv/render/mesh_frag.h"
#include "hmsm_spirv/render/mesh_vert.h"
#include "hmsm_spirv/render/skinned_vert.h"

#include <span>

namespace hmsm::render {

using namespace internal;

namespace {

int find_memory_type(const VkPhysicalDeviceMemoryProperties& memory, uint32_t bits,
                     VkMemoryPropertyFlags wanted) {
    for (uint32_t i = 0; i < memory.memoryTypeCount; ++i)
        if ((bits & (1u << i)) && (memory.memoryTypes[i].propertyFlags & wanted) == wanted) return int(i);
    return -1;
}

}  // namespace

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

    // 0: the frame constants; 1: the vertex positions again, as a storage buffer (leaf scale);
    // skinned instead of 1: 2 the bind vertices, 3 the inverse binds, 4 the joints (skinned.cpp).
    std::vector<VkDescriptorSetLayoutBinding> bindings(1);
    bindings[0].binding = 0;
    bindings[0].descriptorType = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
    bindings[0].descriptorCount = 1;
    bindings[0].stageFlags = VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT;
    skinned = settings.draw == DrawMode::skinned;
    for (uint32_t b : skinned ? std::vector<uint32_t>{2, 3, 4} : std::vector<uint32_t>{1}) {
        VkDescriptorSetLayoutBinding storage{};
        storage.binding = b;
        storage.descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
        storage.descriptorCount = 1;
        storage.stageFlags = VK_SHADER_STAGE_VERTEX_BIT;
        bindings.push_back(storage);
    }
    VkDescriptorSetLayoutCreateInfo layout{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
    layout.bindingCount = uint32_t(bindings.size());
    layout.pBindings = bindings.data();
    HMSM_VK_TRY(vk().vkCreateDescriptorSetLayout(dev(), &layout, nullptr, &set_layout));

    VkDescriptorPoolSize sizes[2] = {{VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 1},
                                     {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, uint32_t(bindings.size() - 1)}};
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
    // The storage bindings are written by create_geometry() once the vertex buffers exist.
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
                                               skinned ? std::span<const uint32_t>(hmsm_spirv_render_skinned_vert)
                                                       : std::span<const uint32_t>(hmsm_spirv_render_mesh_vert),
                                               hmsm_spirv_render_mesh_frag};
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
        if (mesh && !skinned) {  // skinned.vert reads its bind vertices from a storage buffer
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

}  // namespace hmsm::render
