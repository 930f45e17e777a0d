#include "render/renderer_state.h"

#include <cstring>

namespace hmsm::render {

using namespace internal;

void Renderer::State::record_draws(VkCommandBuffer cmd) {
    const VolkDeviceTable& t = vk();
    t.vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline_layout, 0, 1,
                              &descriptor_set, 0, nullptr);
    t.vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, backdrop);
    t.vkCmdDraw(cmd, 3, 1, 0, 0);
    if (!settings.draw_trees || instances.empty()) return;

    if (!skinned) {  // skinned.vert reads its bind vertices from a storage buffer instead
        VkBuffer buffers[2] = {positions, normals};
        VkDeviceSize offsets[2] = {positions_offset, normals_offset};
        t.vkCmdBindVertexBuffers(cmd, 0, 2, buffers, offsets);
    }
    t.vkCmdBindIndexBuffer(cmd, indices.handle(), 0, VK_INDEX_TYPE_UINT32);
    const int32_t flags = (samples != VK_SAMPLE_COUNT_1_BIT ? kFlagAlphaToCoverage : 0) |
                          (packed_normals ? kFlagPackedNormals : 0);
    auto draw_all = [&](int32_t bark_mode, int32_t leaf_mode) {
        for (size_t i = 0; i < instances.size(); ++i) {
            const ModelDraw& m = models[instances[i].first];
            const int32_t first_vertex = int32_t(instances[i].second);
            DrawConstants c{bark_mode, first_vertex + int32_t(m.vertices - m.leaf_vertices), int32_t(i), flags,
                            skinned ? instance_chain_base[i] : 0,
                            skinned ? model_bind_base[instances[i].first] : 0, {0, 0}};
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

Status Renderer::render(uint32_t steps, Image& image) {
    State& s = *state_;
    const VolkDeviceTable& t = s.vk();
    if (s.source == VertexSource::host_upload) {
        if (steps) HMSM_TRY(s.simulation->step(steps));
        HMSM_TRY(s.skinned ? s.upload_joints() : s.upload_vertices());
    }
    VkCommandBuffer cmd = s.command_buffer;
    HMSM_VK_TRY(t.vkResetCommandBuffer(cmd, 0));
    VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    HMSM_VK_TRY(t.vkBeginCommandBuffer(cmd, &begin));
    if (s.source == VertexSource::device_buffers) {
        // The previous frame's vertex fetches (skinned: the vertex shader's reads of the joint
        // buffer) finish before the steps overwrite the buffers...
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
        // ...and the vertex fetches (or joint reads) of this frame see what the steps (or
        // earlier work) wrote.
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

}  // namespace hmsm::render
