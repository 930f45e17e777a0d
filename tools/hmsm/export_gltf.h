// hmsm export --gltf: one instance's animation as a skinned glTF 2.0 binary (docs/model.md 3.10
// and 5). The skin is the mesh template of pass 7 bound to one joint per chain; the clip animates
// only the joints' rotations, one key per frame.
#pragma once

#include <hmsm/hmsm.h>

#include <CLI/CLI.hpp>

#include <glm/gtc/quaternion.hpp>
#include <glm/mat4x4.hpp>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace hmsm::cli {

/// The bind pose of docs/model.md 3.10: the model's rest pose as an instance at the origin with
/// yaw 0 (p̄ = p − p_root). Vertices in MeshTemplate order (branch rings and tips, then leaf
/// cards); joint j is chain j.
struct SkinTemplate {
    std::vector<glm::dvec3> positions;  ///< bind position p̄_attach(c) + B_c v_local
    std::vector<glm::dvec3> normals;    ///< bind normal B_c n_local (unit)
    /// Joints with non-zero weight first; unused slots are joint 0 with weight 0.
    std::vector<std::array<uint16_t, 4>> joints;
    std::vector<std::array<double, 4>> weights;
    std::vector<glm::dmat4> inverse_bind;      ///< per chain: [B_cᵀ | −B_cᵀ p̄_attach(c)]
    /// Per chain: the constant translation relative to the parent joint,
    /// B_parentᵀ (p̄_attach(c) − p̄_attach(parent)); the trunk's is 0 (the exporter puts the
    /// instance origin there).
    std::vector<glm::dvec3> joint_translation;
    uint32_t leaf_vertex_count = 0;  ///< the last vertices: 4 per leaf card
    uint32_t leaf_index_count = 0;   ///< the last indices: 6 per leaf card
};

/// A skin of the library's build_skin (of the model, or of a level of detail) in glTF's terms;
/// `joints` is the hierarchy its joints are the chains of (the model's or the level's). Fails
/// (invalid_argument) with more joints than a glTF JOINTS_0 accessor of unsigned shorts can name.
Result<SkinTemplate> derive_skin(const hmsm::SkinTemplate& bind, const Hierarchy& joints,
                                 const MeshTemplate& mesh);

/// Frames of a clip of `seconds` at `fps`: k = 0 … ⌊seconds·fps + 1e-9⌋.
uint64_t export_frame_count(double seconds, double fps);
/// Frame k is the state after ⌊k / (fps·dt) + 0.5 + 1e-9⌋ steps.
uint64_t export_frame_steps(uint64_t frame, double fps, double dt);

/// The animated joint rotations: per frame, per chain, the rotation relative to the parent joint
/// (trunk: R_0; others: T_c = R_parentᵀ R_c), as unit quaternions whose consecutive keys per
/// joint have a non-negative dot product.
struct JointClip {
    double fps = 24.0;
    std::vector<std::vector<glm::dquat>> rotations;  ///< [frame][chain]
};

/// Appends one frame from the column-major chain rotations R_c of one instance (9 per chain, as
/// Simulation::read(Output::chain_rotations) gives them), keeping signs continuous.
void append_clip_frame(JointClip& clip, const Hierarchy& hierarchy,
                       const std::vector<double>& chain_rotations);

/// Builds the GLB bytes: joints (the chain tree), the skinned mesh (bark and leaf primitives and
/// materials), inverse bind matrices and the clip. `origin` is the trunk joint's translation.
Result<std::string> build_glb(const Hierarchy& hierarchy, const MeshTemplate& mesh,
                              const SkinTemplate& skin, const JointClip& clip,
                              const glm::dvec3& origin, const std::string& name);

/// The subcommand (cmd_export.cpp): registers its flags, then runs after parsing.
void register_export_flags(CLI::App& app);
int run_export(CLI::App& app);

}  // namespace hmsm::cli
