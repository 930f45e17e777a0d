// Host side of DrawMode::skinned: the skins of a simulation's models and linear-blend skinning
// on the host, the same sum as shaders/glsl/skinning.glsl (docs/skinning.md). The renderer
// frames its camera with it; tests check it against pass 7.
#pragma once

#include <hmsm/simulation.h>
#include <hmsm/skin.h>
#include <hmsm/status.h>

#include <span>
#include <vector>

namespace hmsm::render {

/// build_skin() for every model of the simulation's scene, with its config's model options.
std::vector<SkinTemplate> build_skins(const Simulation& simulation);

/// Skins every instance's bind mesh with `joints` (Output::joint_matrices: 12 floats per
/// chain, instance-major) into `xyz` (3 floats per vertex, in Simulation::read()'s order):
/// hmsm::skin_vertices per instance. invalid_argument when the joint count is not the
/// simulation's chain count.
Status skin_on_host(const Simulation& simulation, const std::vector<SkinTemplate>& skins,
                    std::span<const float> joints, std::vector<float>& xyz);

}  // namespace hmsm::render
