// The glTF mapping of docs/model.md 3.10: skin derivation, clip frames and the GLB itself.
#include "export_gltf.h"

#include <tiny_gltf.h>

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <exception>
#include <limits>
#include <sstream>

namespace hmsm::cli {

Result<SkinTemplate> derive_skin(const hmsm::SkinTemplate& bind, const Hierarchy& h, const MeshTemplate& mesh) {
    const size_t chains = h.chains.size();
    if (chains > size_t(std::numeric_limits<uint16_t>::max()) + 1)
        return Status{ErrorCode::invalid_argument,
                      "the tree has " + std::to_string(chains) +
                          " chains; a glTF skin here names at most 65536 joints (--max-joints sets fewer)"};
    if (bind.inverse_bind.size() != chains || bind.vertices.size() != mesh.vertices.size())
        return Status{ErrorCode::internal, "export: the skin does not match its joints or mesh"};
    // The library's skin (bind pose, joints and weights, inverse bind matrices), in glTF's terms.
    SkinTemplate skin;
    skin.inverse_bind.resize(chains);
    skin.joint_translation.resize(chains, glm::dvec3(0.0));
    for (size_t c = 0; c < chains; ++c) {
        // Row-major 3x4 [B_cᵀ | −B_cᵀ p̄_attach(c)] to a column-major glm matrix.
        const auto& rows = bind.inverse_bind[c];
        glm::dmat4 inverse(1.0);
        for (int r = 0; r < 3; ++r)
            for (int col = 0; col < 4; ++col) inverse[col][r] = rows[size_t(r * 4 + col)];
        skin.inverse_bind[c] = inverse;
        // The bind joint matrix [B_c | p̄_attach(c)] gives the constant translation relative to
        // the parent joint, B_parentᵀ (p̄_attach(c) − p̄_attach(parent)).
        const int32_t parent = h.chains[c].parent;
        if (parent >= 0) {
            const auto& own = bind.bind[c];
            const auto& up = bind.bind[size_t(parent)];
            const glm::dvec3 offset(own[3] - up[3], own[7] - up[7], own[11] - up[11]);
            skin.joint_translation[c] = glm::transpose(glm::dmat3(h.chains[size_t(parent)].frame)) * offset;
        }
    }
    const size_t count = bind.vertices.size();
    skin.positions.resize(count);
    skin.normals.resize(count);
    skin.joints.resize(count);
    skin.weights.resize(count);
    for (size_t i = 0; i < count; ++i) {
        const SkinVertex& v = bind.vertices[i];
        skin.positions[i] = glm::dvec3(v.position);
        skin.normals[i] = glm::dvec3(v.normal);
        // Only joints of non-zero weight are listed (a glTF vertex names no joint of weight 0).
        std::array<uint16_t, 4> joints{0, 0, 0, 0};
        std::array<double, 4> weights{0.0, 0.0, 0.0, 0.0};
        int slot = 0;
        for (size_t j = 0; j < v.joints.size(); ++j) {
            if (v.joints[j] < 0 || v.weights[j] == 0.0) continue;
            joints[size_t(slot)] = uint16_t(v.joints[j]);
            weights[size_t(slot++)] = v.weights[j];
        }
        skin.joints[i] = joints;
        skin.weights[i] = weights;
    }
    skin.leaf_vertex_count = 4 * mesh.leaf_count;
    skin.leaf_index_count = 6 * mesh.leaf_count;
    return skin;
}

uint64_t export_frame_count(double seconds, double fps) {
    return uint64_t(std::floor(seconds * fps + 1e-9)) + 1;
}

uint64_t export_frame_steps(uint64_t frame, double fps, double dt) {
    return uint64_t(std::floor(double(frame) / (fps * dt) + 0.5 + 1e-9));
}

void append_clip_frame(JointClip& clip, const Hierarchy& h, const std::vector<double>& r) {
    const size_t chains = h.chains.size();
    auto rotation = [&](size_t c) {
        glm::dmat3 m;
        for (int col = 0; col < 3; ++col)
            for (int row = 0; row < 3; ++row) m[col][row] = r[9 * c + 3 * col + row];
        return m;
    };
    std::vector<glm::dquat> frame(chains);
    for (size_t c = 0; c < chains; ++c) {
        const int32_t parent = h.chains[c].parent;
        // The joint's rotation relative to its parent joint: T_c = R_parentᵀ R_c (in double;
        // R is orthonormal, so its transpose is its inverse); the trunk joint's is R_0.
        const glm::dmat3 local =
            parent < 0 ? rotation(c) : glm::transpose(rotation(size_t(parent))) * rotation(c);
        glm::dquat q = glm::normalize(glm::quat_cast(local));
        // q and −q are the same rotation; LINEAR interpolation between keys of opposite sign
        // would swing the long way round.
        if (!clip.rotations.empty() && glm::dot(clip.rotations.back()[c], q) < 0.0) q = -q;
        frame[c] = q;
    }
    clip.rotations.push_back(std::move(frame));
}

namespace {

/// Accumulates the one binary buffer of the GLB, one buffer view per call.
class BinaryBuilder {
public:
    explicit BinaryBuilder(tinygltf::Model& model) : model_(model) {}

    template <class T>
    int view(const std::vector<T>& data, int target, size_t stride = 0) {
        auto& bytes = model_.buffers[0].data;
        while (bytes.size() % 4) bytes.push_back(0);  // every component here is 2 or 4 bytes
        tinygltf::BufferView v;
        v.buffer = 0;
        v.byteOffset = bytes.size();
        v.byteLength = data.size() * sizeof(T);
        v.target = target;
        v.byteStride = stride;  // vertex views: two primitives' accessors share them
        const auto* p = reinterpret_cast<const unsigned char*>(data.data());
        bytes.insert(bytes.end(), p, p + v.byteLength);
        model_.bufferViews.push_back(std::move(v));
        return int(model_.bufferViews.size() - 1);
    }

    int accessor(int view, size_t byte_offset, int component, size_t count, int type,
                 std::vector<double> min = {}, std::vector<double> max = {}) {
        tinygltf::Accessor a;
        a.bufferView = view;
        a.byteOffset = byte_offset;
        a.componentType = component;
        a.count = count;
        a.type = type;
        a.minValues = std::move(min);
        a.maxValues = std::move(max);
        model_.accessors.push_back(std::move(a));
        return int(model_.accessors.size() - 1);
    }

private:
    tinygltf::Model& model_;
};

tinygltf::Material material(const char* name, std::vector<double> colour, double roughness,
                            bool double_sided) {
    tinygltf::Material m;
    m.name = name;
    m.pbrMetallicRoughness.baseColorFactor = std::move(colour);
    m.pbrMetallicRoughness.metallicFactor = 0.0;
    m.pbrMetallicRoughness.roughnessFactor = roughness;
    m.doubleSided = double_sided;
    m.alphaMode = "OPAQUE";  // untextured cards: no alpha to cut out
    return m;
}

std::vector<double> quaternion_xyzw(const glm::quat& q) { return {q.x, q.y, q.z, q.w}; }

}  // namespace

Result<std::string> build_glb(const Hierarchy& h, const MeshTemplate& mesh, const SkinTemplate& skin,
                              const JointClip& clip, const glm::dvec3& origin, const std::string& name) {
    const size_t chains = h.chains.size();
    const size_t frames = clip.rotations.size();
    const size_t vertex_count = mesh.vertices.size();
    if (frames == 0 || chains == 0 || vertex_count == 0)
        return Status{ErrorCode::internal, "export: empty clip or mesh"};

    tinygltf::Model model;
    model.asset.version = "2.0";
    model.asset.generator = "hmsm export";
    model.buffers.resize(1);
    BinaryBuilder bin(model);

    // Vertex attributes, float32 (joints unsigned short), in MeshTemplate order.
    std::vector<float> positions(3 * vertex_count), normals(3 * vertex_count), weights(4 * vertex_count);
    std::vector<uint16_t> joints(4 * vertex_count);
    for (size_t i = 0; i < vertex_count; ++i) {
        for (int k = 0; k < 3; ++k) {
            positions[3 * i + k] = float(skin.positions[i][k]);
            normals[3 * i + k] = float(skin.normals[i][k]);
        }
        for (int k = 0; k < 4; ++k) {
            joints[4 * i + k] = skin.joints[i][k];
            weights[4 * i + k] = float(skin.weights[i][k]);
        }
    }
    const int position_view = bin.view(positions, TINYGLTF_TARGET_ARRAY_BUFFER, 12);
    const int normal_view = bin.view(normals, TINYGLTF_TARGET_ARRAY_BUFFER, 12);
    const int joint_view = bin.view(joints, TINYGLTF_TARGET_ARRAY_BUFFER, 8);
    const int weight_view = bin.view(weights, TINYGLTF_TARGET_ARRAY_BUFFER, 16);

    // Bark and leaves are two primitives over consecutive vertex ranges (the leaf cards are the
    // template's last vertices and triangles); each primitive's indices start at its own range.
    const uint32_t leaf_first = uint32_t(vertex_count - skin.leaf_vertex_count);
    const size_t leaf_index_first = mesh.indices.size() - skin.leaf_index_count;
    std::vector<uint32_t> indices(mesh.indices.begin(), mesh.indices.end());
    for (size_t i = leaf_index_first; i < indices.size(); ++i) indices[i] -= leaf_first;
    const int index_view = bin.view(indices, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);

    model.materials.push_back(material("bark", {0.36, 0.25, 0.17, 1.0}, 0.9, false));
    model.materials.push_back(material("leaves", {0.24, 0.50, 0.13, 1.0}, 0.7, true));

    tinygltf::Mesh gltf_mesh;
    gltf_mesh.name = name;
    auto primitive = [&](uint32_t first, uint32_t count, size_t index_first, size_t index_count,
                         int material_index) {
        std::vector<double> lo(3, std::numeric_limits<double>::infinity()), hi(3, -lo[0]);
        for (size_t i = first; i < first + count; ++i)
            for (int k = 0; k < 3; ++k) {
                lo[k] = std::min<double>(lo[k], positions[3 * i + k]);
                hi[k] = std::max<double>(hi[k], positions[3 * i + k]);
            }
        tinygltf::Primitive p;
        p.mode = TINYGLTF_MODE_TRIANGLES;
        p.material = material_index;
        p.attributes["POSITION"] = bin.accessor(position_view, 12 * size_t(first), TINYGLTF_COMPONENT_TYPE_FLOAT,
                                                count, TINYGLTF_TYPE_VEC3, lo, hi);
        p.attributes["NORMAL"] = bin.accessor(normal_view, 12 * size_t(first), TINYGLTF_COMPONENT_TYPE_FLOAT,
                                              count, TINYGLTF_TYPE_VEC3);
        p.attributes["JOINTS_0"] = bin.accessor(joint_view, 8 * size_t(first),
                                                TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, count, TINYGLTF_TYPE_VEC4);
        p.attributes["WEIGHTS_0"] = bin.accessor(weight_view, 16 * size_t(first), TINYGLTF_COMPONENT_TYPE_FLOAT,
                                                 count, TINYGLTF_TYPE_VEC4);
        p.indices = bin.accessor(index_view, 4 * index_first, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT,
                                 index_count, TINYGLTF_TYPE_SCALAR);
        gltf_mesh.primitives.push_back(std::move(p));
    };
    primitive(0, leaf_first, 0, leaf_index_first, 0);
    if (skin.leaf_vertex_count > 0)
        primitive(leaf_first, skin.leaf_vertex_count, leaf_index_first, skin.leaf_index_count, 1);
    model.meshes.push_back(std::move(gltf_mesh));

    // Joint nodes: node c is chain c's joint (so joint index = chain id = node index); the
    // hierarchy is the chain tree. Translations are constant; rotations start at frame 0.
    std::vector<glm::quat> keys(frames * chains);  // per joint, its frames (float32, as stored)
    for (size_t f = 0; f < frames; ++f)
        for (size_t c = 0; c < chains; ++c) keys[c * frames + f] = glm::quat(clip.rotations[f][c]);
    model.nodes.resize(chains + 1);
    for (size_t c = 0; c < chains; ++c) {
        tinygltf::Node& node = model.nodes[c];
        node.name = "chain_" + std::to_string(c);
        const glm::dvec3 t = c == 0 ? origin : skin.joint_translation[c];
        node.translation = {t.x, t.y, t.z};
        node.rotation = quaternion_xyzw(keys[c * frames]);
        if (h.chains[c].parent >= 0) model.nodes[size_t(h.chains[c].parent)].children.push_back(int(c));
    }
    // The skinned mesh node: a scene root without a transform (skinning ignores it anyway).
    tinygltf::Node& mesh_node = model.nodes[chains];
    mesh_node.name = name;
    mesh_node.mesh = 0;
    mesh_node.skin = 0;

    std::vector<float> inverse_bind(16 * chains);
    for (size_t c = 0; c < chains; ++c)
        for (int col = 0; col < 4; ++col)
            for (int row = 0; row < 4; ++row) inverse_bind[16 * c + 4 * col + row] = float(skin.inverse_bind[c][col][row]);
    tinygltf::Skin gltf_skin;
    gltf_skin.name = name;
    gltf_skin.skeleton = 0;
    gltf_skin.inverseBindMatrices = bin.accessor(bin.view(inverse_bind, 0), 0, TINYGLTF_COMPONENT_TYPE_FLOAT,
                                                 chains, TINYGLTF_TYPE_MAT4);
    for (size_t c = 0; c < chains; ++c) gltf_skin.joints.push_back(int(c));
    model.skins.push_back(std::move(gltf_skin));

    // The clip: key k at t = k / fps, one LINEAR rotation sampler per joint over shared times.
    std::vector<float> times(frames);
    for (size_t f = 0; f < frames; ++f) times[f] = float(double(f) / clip.fps);
    for (size_t f = 1; f < frames; ++f)
        if (!(times[f] > times[f - 1]))
            return Status{ErrorCode::invalid_argument,
                          "--fps " + std::to_string(clip.fps) + ": frame times " + std::to_string(f - 1) +
                              " and " + std::to_string(f) + " are equal in float32; lower --fps or --seconds"};
    const int time_accessor =
        bin.accessor(bin.view(times, 0), 0, TINYGLTF_COMPONENT_TYPE_FLOAT, frames, TINYGLTF_TYPE_SCALAR,
                     {double(times.front())}, {double(times.back())});
    std::vector<float> key_values(4 * keys.size());
    for (size_t i = 0; i < keys.size(); ++i) {
        key_values[4 * i + 0] = keys[i].x;
        key_values[4 * i + 1] = keys[i].y;
        key_values[4 * i + 2] = keys[i].z;
        key_values[4 * i + 3] = keys[i].w;
    }
    const int key_view = bin.view(key_values, 0);
    tinygltf::Animation animation;
    animation.name = "wind";
    for (size_t c = 0; c < chains; ++c) {
        tinygltf::AnimationSampler sampler;
        sampler.input = time_accessor;
        sampler.output = bin.accessor(key_view, 16 * frames * c, TINYGLTF_COMPONENT_TYPE_FLOAT, frames,
                                      TINYGLTF_TYPE_VEC4);
        sampler.interpolation = "LINEAR";
        animation.samplers.push_back(sampler);
        tinygltf::AnimationChannel channel;
        channel.sampler = int(c);
        channel.target_node = int(c);
        channel.target_path = "rotation";
        animation.channels.push_back(std::move(channel));
    }
    model.animations.push_back(std::move(animation));

    tinygltf::Scene scene;
    scene.name = name;
    scene.nodes = {int(chains), 0};
    model.scenes.push_back(std::move(scene));
    model.defaultScene = 0;

    while (model.buffers[0].data.size() % 4) model.buffers[0].data.push_back(0);
    if (model.buffers[0].data.size() > (size_t(1) << 31))
        return Status{ErrorCode::invalid_argument,
                      "the clip needs " + std::to_string(model.buffers[0].data.size() >> 20) +
                          " MiB, more than a GLB holds here (2 GiB): lower --seconds or --fps"};
    try {
        std::ostringstream out;
        tinygltf::TinyGLTF writer;
        if (!writer.WriteGltfSceneToStream(&model, out, false, true))
            return Status{ErrorCode::internal, "export: the glTF writer failed"};
        return out.str();
    } catch (const std::exception& e) {
        return Status{ErrorCode::internal, std::string("export: the glTF writer failed: ") + e.what()};
    }
}

}  // namespace hmsm::cli
