#include "device_words.h"

#include <cstring>
#include <type_traits>

namespace hmsm::detail {
namespace {

template <class T>
std::vector<std::byte> raw_bytes(const std::vector<T>& values) {
    std::vector<std::byte> bytes(values.size() * sizeof(T));
    if (!values.empty()) std::memcpy(bytes.data(), values.data(), bytes.size());
    return bytes;
}

std::vector<std::byte> float4_image(const std::vector<glm::dvec4>& values) {
    std::vector<float> words(values.size() * 4);
    for (size_t i = 0; i < values.size(); ++i)
        for (int k = 0; k < 4; ++k) words[4 * i + k] = float(values[i][k]);
    return raw_bytes(words);
}

/// Matrices as three vec4 columns; column 0's w holds `column0_w` (empty: 0).
std::vector<std::byte> mat3x4_image(const std::vector<glm::dmat3>& values,
                                    const std::vector<uint32_t>& column0_w = {}) {
    std::vector<float> words(values.size() * 12, 0.0f);
    for (size_t i = 0; i < values.size(); ++i) {
        for (int c = 0; c < 3; ++c)
            for (int r = 0; r < 3; ++r) words[12 * i + 4 * c + r] = float(values[i][c][r]);
        if (i < column0_w.size()) words[12 * i + 3] = float(column0_w[i]);
    }
    return raw_bytes(words);
}

}  // namespace

namespace {
std::vector<std::byte> padded(std::vector<std::byte> image, const SceneData& d, BufferId id) {
    image.resize(d.element_count(id) * device_element_bytes(id), std::byte{0});
    return image;
}
/// Records of `vec4s` vec4 per model chain, held record by record, as floats stored by vec4:
/// vec4 j of chain c at j * chains + c (gpu_layout.h).
std::vector<std::byte> by_vec4(const std::vector<double>& records, size_t vec4s) {
    const size_t chains = records.size() / (4 * vec4s);
    std::vector<float> words(records.size());
    for (size_t c = 0; c < chains; ++c)
        for (size_t j = 0; j < vec4s; ++j)
            for (size_t k = 0; k < 4; ++k) words[4 * (j * chains + c) + k] = float(records[4 * (vec4s * c + j) + k]);
    return raw_bytes(words);
}
}  // namespace

std::vector<std::byte> device_image(const SceneData& d, BufferId id) {
    static_assert(sizeof(glm::ivec2) == 8, "ivec2 must be two packed int32");
    switch (id) {
        case BufferId::chain_parent: return raw_bytes(d.chain_parent);
        case BufferId::chain_jump: return raw_bytes(d.chain_jump);
        case BufferId::chain_walk: return raw_bytes(d.chain_walk);
        case BufferId::chain_attach: return raw_bytes(d.chain_attach);
        case BufferId::chain_rest_rotation: return mat3x4_image(d.chain_rest_rotation, d.chain_keep_level);
        case BufferId::chain_constants: return float4_image(d.chain_constants);
        case BufferId::node_owner: return raw_bytes(d.node_owner);
        case BufferId::node_local: return float4_image(d.node_local);
        case BufferId::vertex_chain: return raw_bytes(d.vertex_chain);
        case BufferId::vertex_rest_position: return float4_image(d.vertex_rest_position);
        case BufferId::vertex_rest_normal: return float4_image(d.vertex_rest_normal);
        case BufferId::vertex_parent_position: return float4_image(d.vertex_parent_position);
        case BufferId::vertex_parent_normal: return float4_image(d.vertex_parent_normal);
        // The coupled dynamics' records of its exchange, as floats, by vec4 (gpu_layout.h).
        case BufferId::chain_dynamics:
            if (d.articulated()) return by_vec4(d.chain_articulated, HMSM_CHAIN_ARTICULATED_VEC4S);
            return by_vec4(d.chain_dynamics, HMSM_CHAIN_DYNAMICS_VEC4S);
        // Instance buffers: the live instances, then zeros up to the capacity.
        case BufferId::instance_origin: return padded(float4_image(d.instance_origin), d, id);
        case BufferId::instance_yaw: return padded(float4_image(d.instance_yaw), d, id);
        case BufferId::instance_wind: {
            std::vector<float> words(d.instance_wind.begin(), d.instance_wind.end());
            return padded(raw_bytes(words), d, id);
        }
        // The listed dispatches' table: written with a program that lists instances.
        case BufferId::instance_table: return padded({}, d, id);
        default: return {};  // state buffers start zeroed on the device
    }
}

void words_to_scalars(Shape shape, const void* words, uint64_t n, void* dst, Scalar as) {
    const bool integer = shape_is_integer(shape);
    const auto* ints = static_cast<const int32_t*>(words);
    const auto* floats = static_cast<const float*>(words);
    if (as == Scalar::f64) {
        auto* out = static_cast<double*>(dst);
        for (uint64_t i = 0; i < n; ++i) out[i] = integer ? double(ints[i]) : double(floats[i]);
    } else if (integer) {
        auto* out = static_cast<float*>(dst);
        for (uint64_t i = 0; i < n; ++i) out[i] = float(ints[i]);
    } else {
        std::memcpy(dst, words, n * 4);  // the same words, bit for bit
    }
}

void scalars_to_words(Shape shape, const void* src, uint64_t n, void* words, Scalar as) {
    // One loop per case, each a plain conversion the compiler vectorizes (the instance table and
    // a switch's state are millions of scalars at 500,000 trees).
    auto convert = [n](const auto* from, auto* to) {
        using To = std::remove_pointer_t<decltype(to)>;
        for (uint64_t i = 0; i < n; ++i) to[i] = To(from[i]);
    };
    const bool integer = shape_is_integer(shape);
    if (as == Scalar::f64) {
        const auto* from = static_cast<const double*>(src);
        if (integer) convert(from, static_cast<int32_t*>(words));
        else convert(from, static_cast<float*>(words));
    } else {
        const auto* from = static_cast<const float*>(src);
        if (integer) convert(from, static_cast<int32_t*>(words));
        else if (n > 0) std::memcpy(words, from, n * 4);  // the same words, bit for bit
    }
}

}  // namespace hmsm::detail
