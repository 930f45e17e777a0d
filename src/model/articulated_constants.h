// The records of the coupled dynamics' articulated exchange (docs/model.md 3.13, "The
// articulated exchange"; gpu_layout.h HMSM_CHAIN_ARTICULATED_VEC4S): each chain's articulated
// inertia from the leaves up (every body's scaled so that the step sways the tree's fundamental
// at its frequency), the joints' armature of the theta step, folded on the host in double.
#pragma once

#include <hmsm/hierarchy.h>

#include <vector>

namespace hmsm::detail {

/// The theta of the step of a joint whose chain sways at f0 (Hz) at step dt (s):
/// clamp(pi f0 dt, 1/2, 1), the implicit midpoint rule where the step resolves the sway and the
/// implicit Euler step, which does not ring, where it does not.
double articulated_theta(double frequency, double dt);

/// A joint's structural damping under the exchange: 2 zeta_s sqrt(K I_rigid), the rigid body
/// beyond the joint on its spring damped at zeta_s (a link's held record takes I = K / omega0^2
/// instead, which would damp a split chain's higher modes in proportion to their frequency).
double articulated_damping(const ChainDynamics& d, int axis);

/// The whole tree's sway frequency (Hz) from Rayleigh's quotient with its static deflection
/// under a uniform lateral acceleration, omega^2 = q^T F / q^T M q with q = K^-1 F, the lower of
/// the model's x and z directions: the frequency of its fundamental mode to within a percent or
/// two (docs/model.md 3.13, "The step").
double whole_tree_sway_hz(const Hierarchy& h);

/// The factor r = (x / tan x)^2, x = min(pi f dt, 1/2), by which the exchange scales every
/// body's inertia so that the implicit midpoint rule sways the tree's fundamental mode of f (Hz)
/// at f, not at (1 / (pi dt)) atan(pi f dt).
double articulated_inertia_scale(double frequency, double dt);

/// Appends the records of every chain of `h` (built under Dynamics::coupled) for step dt.
void append_articulated_records(const Hierarchy& h, double dt, std::vector<double>& out);

}  // namespace hmsm::detail
