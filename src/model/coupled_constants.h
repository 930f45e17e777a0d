// The per-chain constants of the coupled dynamics (docs/model.md 3.13), computed on the host in
// double from the tree's radii and leaves, the material and the foliage.
#pragma once

#include <hmsm/hierarchy.h>
#include <hmsm/options.h>
#include <hmsm/status.h>
#include <hmsm/tree.h>

#include <array>

namespace hmsm::detail {

/// Air density (kg/m^3) and the reference wind speed of strength 1 (m/s, docs/model.md 3.5).
inline constexpr double kAirDensity = 1.225;
inline constexpr double kReferenceWindSpeed = 6.0;
/// Dynamic pressure of strength 1: q_ref = rho_air U_ref^2 / 2 (Pa).
inline constexpr double kReferencePressure = 0.5 * kAirDensity * kReferenceWindSpeed * kReferenceWindSpeed;

/// Under coupled, the trunk is split into kTrunkLinks links and every chain into links of about
/// the same length, at most kMaxLinks (docs/model.md 3.13).
inline constexpr int32_t kTrunkLinks = 6;
inline constexpr int32_t kMaxLinks = 6;

/// Fills chain.dynamics of every chain of `h` (built with Dynamics::coupled from `tree`), and
/// sets the paper fields to axis x's values (hierarchy.h). invalid_argument, naming the chain
/// and its attach node, where a constant leaves the float-safe range of docs/model.md 3.4.
Status fill_coupled_constants(const TreeModel& tree, const Parameters& parameters, Hierarchy& h);

/// The transition of I x'' + D x' + K x = F over dt with F held (docs/model.md 3.13): with
/// y = x - F/K, (y, x')(t + dt) = [a11 a12; a21 a22] (y, x')(t). Returns (a11, a12, a21, a22):
/// exp(A dt) for A = [0 1; -K/I -D/I], by scaling and squaring in double.
std::array<double, 4> oscillator_transition(double inertia, double stiffness, double damping, double dt);

/// First natural frequency (Hz) of a cantilever of length `length` with uniform radius, modulus
/// and density and no load: (1.8751^2 / 2 pi) sqrt(E J / (mu L^4)), J = pi r^4 / 4, mu = rho pi r^2.
double uniform_cantilever_frequency(double length, double radius, const Material& material);

}  // namespace hmsm::detail
