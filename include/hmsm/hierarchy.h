// Chains, frames, local coordinates and per-chain constants (docs/model.md 3.2-3.4): a pure
// function of a validated tree, the model options and the parameters.
#pragma once

#include <hmsm/export.h>

#include <hmsm/options.h>
#include <hmsm/tree.h>
#include <hmsm/types.h>

#include <vector>

namespace hmsm {

struct Chain {
    int32_t parent = -1;       ///< parent chain id, -1 for the trunk
    int32_t depth = 0;         ///< trunk 0
    int32_t attach_node = 0;   ///< node the chain hangs from (owned by the parent chain)
    std::vector<int32_t> members;  ///< member node ids in chain order (the trunk: not the root)
    Mat3 frame{1.0};          ///< rest frame B_c = [x y z]
    Mat3 rest_rotation{1.0};  ///< Q_c = B_parent^T B_c (trunk: B_0)
    double length = 0.0;       ///< L_c, polyline through attach node and members
    double radius = 0.0;       ///< r_c, radius of the first member
    double inertia = 0.0;      ///< I_c (after the frequency cap)
    double stiffness = 0.0;    ///< K_c
    double damping = 0.0;      ///< D_c
    double wind_area = 0.0;    ///< A_c
    bool capped = false;       ///< the frequency cap raised I_c (docs/model.md 3.4)
};

struct Hierarchy {
    std::vector<Chain> chains;           ///< breadth-first: depth never decreases with id
    std::vector<int32_t> node_owner;     ///< chain owning each node (input order)
    std::vector<Vec3> node_local;  ///< l_n = B_c^T (p_n - p_attach(c)); root: 0
    std::vector<int32_t> continuation;   ///< kappa(i), -1 for a node without children
    int32_t max_depth = 0;
    std::vector<int32_t> chains_per_depth;
    int32_t capped_chain_count = 0;      ///< chains whose inertia the frequency cap raised
};

/// Builds the hierarchy. The tree must be valid (validate_tree); options and parameters are
/// validated here.
HMSM_API Result<Hierarchy> build_hierarchy(const TreeModel& tree, const ModelOptions& options,
                                           const Parameters& parameters = {});

}  // namespace hmsm
