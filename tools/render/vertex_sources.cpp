#include "render/renderer_state.h"

#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <tuple>

namespace hmsm::render {

using namespace internal;

namespace {

void copy_matrix(const glm::dmat4& m, float out[16]) {
    const glm::mat4 f(m);
    std::memcpy(out, glm::value_ptr(f), sizeof(float) * 16);
}

}  // namespace

Status Renderer::State::create_geometry() {
    const Scene& scene = simulation->scene();
    std::vector<uint32_t> all_indices;
    models.resize(scene.models.size());
    for (uint32_t m = 0; m < scene.models.size(); ++m) {
        const MeshTemplate& mesh = simulation->mesh(m);
        ModelDraw& draw = models[m];
        draw.first_index = uint32_t(all_indices.size());
        draw.leaf_indices = 6 * mesh.leaf_count;  // leaf cards come last (src/model/mesh.cpp)
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

    if (skinned) return create_skin_sources();  // the bind mesh and the joints (skinned.cpp)
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

// Frames the camera on the current pose (padded for sway) and fills the uniform buffer.
Status Renderer::State::frame_scene() {
    // Skinned draws have no pass 7 to read (Outputs::joints): skin the bind mesh on the host.
    std::vector<float> xyz;
    if (skinned) HMSM_TRY(skinned_positions(xyz));
    else HMSM_TRY(simulation->read(Output::vertex_positions, xyz));
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

}  // namespace hmsm::render
