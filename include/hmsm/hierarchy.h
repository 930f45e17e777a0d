// Chains, frames, local coordinates and per-chain constants (docs/model.md 3.2-3.4): a pure
// function of a validated tree, the model options and the parameters.
#pragma once

#include <hmsm/export.h>

#include <hmsm/options.h>
#include <hmsm/tree.h>
#include <hmsm/types.h>

#include <vector>

namespace hmsm {

/// A chain's constants in the coupled dynamics (docs/model.md 3.13), in SI units; index 0 is
/// the chain's local x axis (theta_x), 1 its local z axis (theta_z).
struct ChainDynamics {
    double mass = 0.0;               ///< own wood and leaves (kg)
    double subtree_mass = 0.0;       ///< with every chain that hangs from it, at any depth
    double drag_area = 0.0;          ///< own wood and leaves, C_d included (m^2)
    double subtree_drag_area = 0.0;  ///< with every chain that hangs from it
    /// M_c: first moment of drag area about the joint, in the chain's rest frame (m^3): own
    /// wood and leaves, and each child's subtree drag area at its attach node.
    Vec3 wind_moment{0.0};
    /// I of the equations of motion (kg m^2): rigid_inertia, or K / omega0^2 for a link of a
    /// split chain (3.13)
    double inertia[2] = {};
    double rigid_inertia[2] = {};    ///< about the joint, everything beyond it lumped (kg m^2)
    /// 1/K = (1/L^2) int (L - s)^2 / (E J(s)) ds (N m/rad), of the whole chain for a link
    double beam_stiffness = 0.0;
    /// f0 of the tapered cantilever with the same load (Hz), of the whole chain for a link
    double frequency[2] = {};
    /// K = (2 pi f0)^2 I, or a link's joint stiffness from E J along the chain (N m/rad)
    double stiffness[2] = {};
    double damping[2] = {};          ///< structural D = 2 zeta_s sqrt(K I) (N m s/rad)
    /// Aerodynamic damping per square root of wind strength: D_aero = aero_damping sqrt(|w|)
    /// + motion_drag |V| (N m s/rad).
    double aero_damping[2] = {};
    /// Drag of the chain's own motion in still air per unit rate: (1/2) rho_air times the third
    /// moment of drag area about the axis (N m s^2/rad^2; docs/model.md 3.13).
    double motion_drag[2] = {};
    /// The chain's own wood and leaves as a rigid body about its joint, in its rest frame:
    /// first mass moment sum m x (kg m), rotational inertia sum m (|x|^2 1 - x x^T) (kg m^2),
    /// and first moment of drag area sum A x (m^3); its mass and drag area are `mass` and
    /// `drag_area` (the articulated exchange, docs/model.md 3.13). In a level of detail
    /// (levels.h) these and `mass`, `drag_area` include the chains folded into the chain.
    Vec3 own_mass_moment{0.0};
    Mat3 own_inertia{0.0};
    Vec3 own_wind_moment{0.0};
    int32_t first_child = 0;         ///< children: chains [first_child, first_child + child_count)
    int32_t child_count = 0;
    /// A chain longer than its tree's link length is split into links (3.13): this chain is link
    /// link_index of link_count; link k + 1 is the last child of link k.
    int32_t link_index = 0;
    int32_t link_count = 0;  ///< 1 for an unsplit chain; 0 under paper
};

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
    /// Dynamics::coupled only (zero under paper). The paper fields above then hold axis x's
    /// I, K and D, and wind_area the largest force per unit wind strength, q_ref |M_c|.
    ChainDynamics dynamics;
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
