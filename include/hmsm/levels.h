// Levels of detail (docs/model.md 3.12): coarser chain hierarchies of one model, for engines
// with a joint budget per skinned mesh and for trees far from the camera. A level folds whole
// subtrees of chains into the chain they hang from, which then carries them rigidly; every
// chain a level keeps moves exactly as in the full model.
#pragma once

#include <hmsm/export.h>

#include <hmsm/hierarchy.h>
#include <hmsm/mesh.h>
#include <hmsm/options.h>
#include <hmsm/status.h>
#include <hmsm/tree.h>

#include <cstdint>
#include <iterator>
#include <vector>

namespace hmsm {

/// Joint budgets of the default levels: 256 (the usual engine limit per skinned mesh), 64, 16
/// and 1, the trunk alone.
inline constexpr int32_t kDefaultJointBudgets[] = {256, 64, 16, 1};

/// One level of detail of a model.
struct DetailLevel {
    int32_t budget = 0;  ///< the joint budget asked for (>= 1)
    /// The level as a model: its chains are the full model's chains it keeps, in their order,
    /// with their frames and constants (I, K, D, A); a kept chain's parent is kept too.
    /// node_owner maps every node to the level chain that moves it, node_local is the node in
    /// that chain's rest frame. `members` list a chain's own path only, as in the full model.
    Hierarchy hierarchy;
    std::vector<int32_t> chain_of;      ///< per full chain, the level chain that moves it
    std::vector<int32_t> source_chain;  ///< per level chain, the full chain it keeps
    double trunk_frequency_hz = 0.0;       ///< f0 = sqrt(K_0 / I_0) / 2π of the level's trunk
    double full_trunk_frequency_hz = 0.0;  ///< the same of the full model
    /// Largest node displacement (m) between the full model and the level in the static
    /// response to a steady wind of strength 1 along +x or +z (docs/model.md 3.12).
    double geometric_error_m = 0.0;

    int32_t joint_count() const { return int32_t(hierarchy.chains.size()); }
    double frequency_ratio() const {
        return full_trunk_frequency_hz > 0.0 ? trunk_frequency_hz / full_trunk_frequency_hz : 1.0;
    }
};

/// The level with at most `max_joints` chains, folding the chains that change the tree least
/// first (docs/model.md 3.12). `full` is build_hierarchy(tree, options, parameters) with the
/// same parameters. max_joints >= the model's chain count returns the full model; below 1
/// (the trunk-only level) it fails with invalid_argument.
HMSM_API Result<DetailLevel> build_level(const TreeModel& tree, const Hierarchy& full,
                                         const Parameters& parameters, int32_t max_joints);

/// One level per distinct budget, finest first (the default budgets: kDefaultJointBudgets).
/// The levels are nested: a coarser level keeps a subset of a finer one's chains. Fails with
/// invalid_argument naming the budget for an empty list or a budget below 1.
HMSM_API Result<std::vector<DetailLevel>> build_levels(const TreeModel& tree, const Hierarchy& full,
                                                       const Parameters& parameters,
                                                       const std::vector<int32_t>& budgets = {
                                                           std::begin(kDefaultJointBudgets),
                                                           std::end(kDefaultJointBudgets)});

/// The model's mesh (build_mesh(tree, full, options)) bound to the level, vertex for vertex:
/// each vertex rigid with the level chain that carries its chain, or, on a base ring whose two
/// chains fall into different level chains, blended between those as in pass 7 (docs/model.md
/// 3.8), its rest position and normal expressed in their frames. At rest it is the model's mesh.
HMSM_API MeshTemplate build_level_mesh(const TreeModel& tree, const Hierarchy& full, const MeshTemplate& mesh,
                                       const DetailLevel& level);

}  // namespace hmsm
