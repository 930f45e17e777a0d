// Skin data (docs/model.md 3.10): everything an engine needs to build its skinned vertex buffer
// once and draw the tree from the joint matrices alone (Output::joint_matrices, or the GPU
// buffers of hmsm/vulkan.h and hmsm/cuda.h), without passes 6 and 7.
#pragma once

#include <hmsm/export.h>
#include <hmsm/hierarchy.h>
#include <hmsm/levels.h>
#include <hmsm/mesh.h>
#include <hmsm/options.h>
#include <hmsm/status.h>
#include <hmsm/tree.h>

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace hmsm {

/// One vertex of the bind pose, skinned to at most two joints (chains).
struct SkinVertex {
    /// Rest position of an instance at the origin with yaw 0: p̄_attach(c) + B_c v_local, with
    /// p̄ = p - p_root.
    Vec3 position{0.0};
    Vec3 normal{0.0};  ///< rest normal B_c n_local (unit)
    /// Joints (chain ids); joints[1] = -1 (weight 0) for a vertex with one joint. A base-ring
    /// vertex of a non-trunk chain has (own chain, 1 - β) and (parent chain, β), β = fix_weight;
    /// β = 0 or 1 leaves only the joint with weight 1. Every other vertex: (own chain, 1).
    std::array<int32_t, 2> joints{0, -1};
    std::array<double, 2> weights{1.0, 0.0};
};

/// The skin of a model's mesh (same vertex order and triangles as its MeshTemplate).
struct SkinTemplate {
    std::vector<SkinVertex> vertices;
    /// Per chain, the inverse bind matrix [B_cᵀ | -B_cᵀ p̄_attach(c)] as 12 numbers row by row
    /// (the layout of Output::joint_matrices), so that
    /// v = Σ_j w_j M_j (inverse_bind_j · (v_bind, 1)) equals pass 7's vertex.
    std::vector<std::array<double, 12>> inverse_bind;
    /// Per chain, the bind (rest) joint matrix [B_c | p̄_attach(c)], row by row.
    std::vector<std::array<double, 12>> bind;
    /// Per chain, its parent chain (-1 for the trunk): the joint hierarchy.
    std::vector<int32_t> parents;
    /// Per joint, the model's chain whose joint matrix drives it: the chain itself in a model's
    /// skin, DetailLevel::source_chain in a level's (which moves exactly as that chain).
    std::vector<int32_t> source_chains;
};

/// Builds the skin of `mesh` (build_mesh(tree, hierarchy, options)).
HMSM_API SkinTemplate build_skin(const TreeModel& tree, const Hierarchy& hierarchy, const MeshTemplate& mesh,
                        const ModelOptions& options);

/// The skin of the same mesh at a level of detail (build_level(tree, hierarchy, ...)): every
/// vertex keeps its bind position and normal, its joints become the level chains that carry
/// them (DetailLevel::chain_of; a vertex whose two joints fall into one level chain keeps that
/// one with weight 1), and the joints are the level's chains, with the inverse bind matrices
/// of the chains they keep. Drawn with the joint matrices of source_chains, it is the full
/// mesh at rest and moves every vertex of a kept chain as the full model does.
HMSM_API SkinTemplate build_skin(const TreeModel& tree, const Hierarchy& hierarchy, const MeshTemplate& mesh,
                                 const ModelOptions& options, const DetailLevel& level);

/// Linear-blend skinning on the CPU of one instance of `skin`'s model (docs/skinning.md), for
/// engines that cannot skin on the GPU: per vertex
///   v = Σ_j w_j M_j (inverse_bind_j (v_bind, 1)),  n = normalize(Σ_j w_j R_j (B_jᵀ n_bind)).
/// `joint_matrices` holds the instance's 12 floats per chain ([R | O] row by row, the layout of
/// Output::joint_matrices from the instance's first chain on; values past its chains are not
/// read). `positions_out` (and `normals_out` unless empty) receive xyz per vertex, in the
/// vertex order of the skin; spans longer than 3 × vertices keep their tail. `threads`: 1
/// runs on the calling thread, 0 on every hardware thread, n on at most n threads.
/// Fails with invalid_argument (naming the span or the chain) for a span too short or a
/// non-finite joint matrix, writing nothing.
HMSM_API Status skin_vertices(const SkinTemplate& skin, std::span<const float> joint_matrices,
                              std::span<float> positions_out, std::span<float> normals_out = {},
                              unsigned threads = 1);

}  // namespace hmsm
