// DrawMode::skinned: the bind mesh of every model uploaded once (bind position and normal,
// two joints and weights per vertex), the inverse bind matrices of every model's chains, and
// the joint palette, bound as storage buffers 2, 3 and 4 of the render set for
// shaders/glsl/render/skinned.vert. The palette is the Vulkan simulation's own joint buffer
// (the frame's compute-to-vertex-shader barrier in frame.cpp orders it) or, for the other
// backends, a host-visible copy of Output::joint_matrices refreshed each frame.
#include "render/renderer_state.h"
#include "render/skinned.h"

#include <algorithm>
#include <cstring>
#include <string>

namespace hmsm::render {

using namespace internal;

namespace {

// One bind vertex as skinned.vert reads it (std430, 48 bytes).
struct GpuSkinVertex {
    float position[4];  // xyz: bind position, w: weight of joints[0]
    float normal[4];    // xyz: bind normal, w: weight of joints[1]
    int32_t joints[4];  // model chain ids (joints[1] = -1: none), 0, 0
};
static_assert(sizeof(GpuSkinVertex) == 48, "std430 layout of SkinVertex in skinned.vert");

}  // namespace

std::vector<SkinTemplate> build_skins(const Simulation& simulation) {
    std::vector<SkinTemplate> skins;
    const Scene& scene = simulation.scene();
    for (uint32_t m = 0; m < scene.models.size(); ++m)
        skins.push_back(build_skin(scene.models[m], simulation.hierarchy(m), simulation.mesh(m),
                                   simulation.config().model));
    return skins;
}

Status skin_on_host(const Simulation& simulation, const std::vector<SkinTemplate>& skins,
                    std::span<const float> joints, std::vector<float>& xyz) {
    if (joints.size() != 12 * simulation.chain_count())
        return {ErrorCode::invalid_argument, "skin: " + std::to_string(joints.size() / 12) +
                                                 " joint matrices for " +
                                                 std::to_string(simulation.chain_count()) + " chains"};
    const auto& instances = simulation.scene().instances;
    size_t vertices = 0;
    for (const Instance& instance : instances) vertices += skins.at(instance.model).vertices.size();
    std::vector<float> skinned(3 * vertices);
    size_t chain_base = 0, vertex_base = 0;
    for (const Instance& instance : instances) {
        const SkinTemplate& skin = skins.at(instance.model);
        HMSM_TRY(skin_vertices(skin, joints.subspan(12 * chain_base),
                               std::span<float>(skinned).subspan(3 * vertex_base, 3 * skin.vertices.size())));
        chain_base += skin.inverse_bind.size();
        vertex_base += skin.vertices.size();
    }
    xyz = std::move(skinned);
    return {};
}

Status Renderer::State::skinned_positions(std::vector<float>& xyz) {
    std::vector<float> palette;
    HMSM_TRY(simulation->read(Output::joint_matrices, palette));
    return skin_on_host(*simulation, skins, palette, xyz);
}

Status Renderer::State::create_skin_sources() {
    skins = build_skins(*simulation);
    std::vector<GpuSkinVertex> vertices;
    std::vector<float> binds;
    for (uint32_t m = 0; m < skins.size(); ++m) {
        const SkinTemplate& skin = skins[m];
        if (skin.vertices.size() != models[m].vertices)
            return {ErrorCode::internal, "render: model " + std::to_string(m) + "'s skin and mesh differ in vertices"};
        // The draws index each model's bind mesh from its first vertex here (record_draws).
        model_bind_base.push_back(int32_t(binds.size() / 12));
        for (const SkinVertex& v : skin.vertices)
            vertices.push_back({{float(v.position.x), float(v.position.y), float(v.position.z), float(v.weights[0])},
                                {float(v.normal.x), float(v.normal.y), float(v.normal.z), float(v.weights[1])},
                                {v.joints[0], v.joints[1], 0, 0}});
        for (const auto& b : skin.inverse_bind)
            for (double x : b) binds.push_back(float(x));
    }
    int64_t model_first = 0;
    std::vector<int64_t> model_vertex_base;
    for (const ModelDraw& draw : models) {
        model_vertex_base.push_back(model_first);
        model_first += draw.vertices;
    }
    int64_t chains = 0;
    for (auto& [model, first_vertex] : instances) {
        first_vertex = model_vertex_base[model];
        instance_chain_base.push_back(int32_t(chains));
        chains += int64_t(skins[model].inverse_bind.size());
    }
    if (uint64_t(chains) != simulation->chain_count())
        return {ErrorCode::internal, "render: skin chain counts do not add up to the simulation's"};

    const VkDeviceSize max_range = device->limits().max_storage_buffer_range;
    const VkDeviceSize vertex_bytes = std::max<VkDeviceSize>(48, vertices.size() * sizeof(GpuSkinVertex));
    const VkDeviceSize bind_bytes = std::max<VkDeviceSize>(48, binds.size() * 4);
    joints_size = std::max<VkDeviceSize>(48, VkDeviceSize(chains) * 48);
    if (vertex_bytes > max_range || bind_bytes > max_range || joints_size > max_range)
        return {ErrorCode::unsupported, "render --draw skinned: the scene's skin or joint buffer exceeds " +
                                            device->name() + "'s storage-buffer range; use --draw vertices"};
    auto transfer = detail::vk::Transfer::create(*device);
    if (!transfer) return transfer.status();
    auto upload = [&](Buffer& out, VkDeviceSize bytes, const void* data, size_t size, const char* name) -> Status {
        auto buffer = Buffer::create(*device, bytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                                     MemoryUse::device_local, name);
        if (!buffer) return buffer.status();
        out = std::move(buffer).value();
        return transfer.value()->upload(out, 0, size, [&](void* dst, VkDeviceSize first, VkDeviceSize n) {
            std::memcpy(dst, static_cast<const uint8_t*>(data) + first, n);
        });
    };
    HMSM_TRY(upload(skin_vertices, vertex_bytes, vertices.data(), vertices.size() * sizeof(GpuSkinVertex),
                    "render skin vertices"));
    HMSM_TRY(upload(inverse_binds, bind_bytes, binds.data(), binds.size() * 4, "render inverse binds"));

    if (simulation->backend_kind() == BackendKind::vulkan) {
        auto handles = hmsm::vulkan::device_handles(*simulation);
        if (!handles) return handles.status();
        if (handles->device != device->handle())
            return {ErrorCode::internal, "render: the Vulkan simulation runs on another device"};
        auto shared = hmsm::vulkan::shared_buffers(*simulation);
        if (!shared) return shared.status();
        if (shared->joint_matrices.stride != 48 || shared->joint_matrices.count != uint64_t(chains))
            return {ErrorCode::internal, "render: the simulation's joint buffer is not one mat3x4 per chain"};
        source = VertexSource::device_buffers;
        joints = shared->joint_matrices.buffer;
        joints_offset = shared->joint_matrices.offset;
        joints_size = std::max<VkDeviceSize>(48, shared->joint_matrices.size);
    } else {
        source = VertexSource::host_upload;
        auto buffer = Buffer::create(*device, joints_size, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryUse::staging,
                                     "render joints");
        if (!buffer) return buffer.status();
        upload_joint_buffer = std::move(buffer).value();
        joints = upload_joint_buffer.handle();
    }
    leaf_scale = settings.leaf_scale;

    VkDescriptorBufferInfo infos[3] = {{skin_vertices.handle(), 0, vertex_bytes},
                                       {inverse_binds.handle(), 0, bind_bytes},
                                       {joints, joints_offset, joints_size}};
    VkWriteDescriptorSet writes[3] = {};
    for (uint32_t i = 0; i < 3; ++i) {
        writes[i] = {VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
        writes[i].dstSet = descriptor_set;
        writes[i].dstBinding = 2 + i;
        writes[i].descriptorCount = 1;
        writes[i].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
        writes[i].pBufferInfo = &infos[i];
    }
    vk().vkUpdateDescriptorSets(dev(), 3, writes, 0, nullptr);
    return {};
}

Status Renderer::State::upload_joints() {
    HMSM_TRY(simulation->read(Output::joint_matrices, host_xyz));
    if (host_xyz.size() != 12 * simulation->chain_count())
        return {ErrorCode::internal, "render: unexpected joint-matrix output size"};
    std::memcpy(upload_joint_buffer.mapped(), host_xyz.data(), host_xyz.size() * sizeof(float));
    return {};
}

}  // namespace hmsm::render
