// Linear-blend skinning on the CPU (include/hmsm/skin.h, docs/skinning.md): each chain's joint
// matrix is composed once with its inverse bind matrix, then every vertex blends the at most two
// composed transforms of its joints.
#include <hmsm/skin.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <string>
#include <system_error>
#include <thread>
#include <vector>

namespace hmsm {
namespace {

using Affine = std::array<double, 12>;  // [R | t] row by row

/// a ∘ b for two affine 3x4 matrices given row by row.
Affine compose(const Affine& a, const Affine& b) {
    Affine out{};
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 4; ++j) {
            double sum = j == 3 ? a[4 * i + 3] : 0.0;
            for (int k = 0; k < 3; ++k) sum += a[4 * i + k] * b[4 * k + j];
            out[4 * i + j] = sum;
        }
    }
    return out;
}

/// Vertices below this count per thread are not worth a thread of their own.
constexpr size_t kVerticesPerThread = 4096;

void skin_range(const SkinTemplate& skin, const std::vector<Affine>& composed, size_t begin, size_t end,
                std::span<float> positions, std::span<float> normals) {
    for (size_t v = begin; v < end; ++v) {
        const SkinVertex& vertex = skin.vertices[v];
        double p[3] = {0.0, 0.0, 0.0}, n[3] = {0.0, 0.0, 0.0};
        for (int j = 0; j < 2; ++j) {
            if (vertex.joints[j] < 0 || vertex.weights[j] == 0.0) continue;
            const Affine& m = composed[static_cast<size_t>(vertex.joints[j])];
            const double w = vertex.weights[j];
            for (int i = 0; i < 3; ++i) {
                const double* row = &m[4 * i];
                p[i] += w * (row[0] * vertex.position.x + row[1] * vertex.position.y +
                             row[2] * vertex.position.z + row[3]);
                n[i] += w * (row[0] * vertex.normal.x + row[1] * vertex.normal.y + row[2] * vertex.normal.z);
            }
        }
        for (int i = 0; i < 3; ++i) positions[3 * v + i] = static_cast<float>(p[i]);
        if (normals.empty()) continue;
        const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        const double scale = length > 0.0 ? 1.0 / length : 0.0;  // no NaN for a degenerate blend
        for (int i = 0; i < 3; ++i) normals[3 * v + i] = static_cast<float>(n[i] * scale);
    }
}

Status bad(std::string message) { return {ErrorCode::invalid_argument, "skin_vertices: " + std::move(message)}; }

}  // namespace

Status skin_vertices(const SkinTemplate& skin, std::span<const float> joint_matrices,
                     std::span<float> positions_out, std::span<float> normals_out, unsigned threads) {
    const size_t chains = skin.inverse_bind.size();
    const size_t vertices = skin.vertices.size();
    if (joint_matrices.size() < 12 * chains)
        return bad("joint_matrices has " + std::to_string(joint_matrices.size()) + " values, 12 x " +
                   std::to_string(chains) + " chains needed");
    if (positions_out.size() < 3 * vertices)
        return bad("positions_out has " + std::to_string(positions_out.size()) + " values, 3 x " +
                   std::to_string(vertices) + " vertices needed");
    if (!normals_out.empty() && normals_out.size() < 3 * vertices)
        return bad("normals_out has " + std::to_string(normals_out.size()) + " values, 3 x " +
                   std::to_string(vertices) + " vertices needed");
    for (size_t v = 0; v < vertices; ++v)
        for (int32_t joint : skin.vertices[v].joints)
            if (joint >= static_cast<int64_t>(chains))
                return bad("vertex " + std::to_string(v) + " names joint " + std::to_string(joint) + " of " +
                           std::to_string(chains) + " chains");

    std::vector<Affine> composed(chains);
    for (size_t c = 0; c < chains; ++c) {
        Affine joint{};
        for (size_t k = 0; k < 12; ++k) {
            joint[k] = joint_matrices[12 * c + k];
            if (!std::isfinite(joint[k]))
                return bad("the joint matrix of chain " + std::to_string(c) + " is not finite");
        }
        composed[c] = compose(joint, skin.inverse_bind[c]);
    }

    size_t workers = threads == 0 ? std::max(1u, std::thread::hardware_concurrency()) : threads;
    workers = std::clamp<size_t>((vertices + kVerticesPerThread - 1) / kVerticesPerThread, 1, workers);
    const size_t chunk = (vertices + workers - 1) / std::max<size_t>(workers, 1);
    std::vector<std::thread> pool;
    size_t begin = chunk;  // the calling thread takes [0, chunk)
    for (; begin < vertices && pool.size() + 1 < workers; begin += chunk) {
        const size_t end = std::min(vertices, begin + chunk);
        try {
            pool.emplace_back(skin_range, std::cref(skin), std::cref(composed), begin, end, positions_out,
                              normals_out);
        } catch (const std::system_error&) {
            break;  // no thread to be had: the calling thread does the rest
        }
    }
    skin_range(skin, composed, 0, std::min(chunk, vertices), positions_out, normals_out);
    if (begin < vertices) skin_range(skin, composed, begin, vertices, positions_out, normals_out);
    for (std::thread& worker : pool) worker.join();
    return {};
}

}  // namespace hmsm
