// The atmospheric wind profile of docs/model.md 3.5 on the host, in double: the mode phases that
// the wind table and instance_wind hand to the devices, and the reference evaluation.
#pragma once

#include <hmsm/options.h>

#include <cstdint>

namespace hmsm::detail {

/// frac(x) = x - floor(x), in [0, 1).
double fraction(double x);

/// Mode k's wander q_k at `clock` (cycles): linear between seeded knot values in [-1/2, 1/2]
/// placed wander_spacing[k] apart in the clock.
double atmospheric_wander(const AtmosphericModes& modes, uint32_t k, double clock);

/// The per-step part of mode k's phase: frac(frac(kx_k clock + u_k) + q_k(clock)), the clock in
/// metres.
double atmospheric_step_phase(const AtmosphericModes& modes, uint32_t k, double clock);

/// The per-instance part of mode k's phase at point x with the instance's wind phase p (metres):
/// frac(kx_k (p - x.e_x) - ky_k x.e_y - kz_k x.e_z), each product reduced mod 1 before the sum,
/// so that no float ever sees more than the fraction.
double atmospheric_instance_phase(const AtmosphericModes& modes, uint32_t k, double p, const Vec3& x,
                                  const WindFrame& frame);

/// sum_{begin <= k < end} a_k cos(2 pi frac(step_k + instance_k)) at `clock`, the instance's
/// phase p and point x: one component's fluctuation, exactly as the devices sum it.
double atmospheric_component(const AtmosphericModes& modes, uint32_t begin, uint32_t end, double clock, double p,
                             const Vec3& x, const WindFrame& frame);

}  // namespace hmsm::detail
