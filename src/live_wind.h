// The wind as the device sees it (docs/model.md 3.5, 3.9; layout in gpu_layout.h): the host
// keeps the clock tau in double and hands every backend only phases reduced mod 2 (periodic
// profiles) or mod 1 (turbulent modes), per step and per instance.
#pragma once

#include <hmsm/options.h>
#include <hmsm/scene.h>
#include <hmsm/config.h>

#include "common/gpu_layout.h"

#include <cstdint>
#include <span>

namespace hmsm::detail {

/// Scalars of one instance's element of instance_wind, of the wind table's header (amplitudes,
/// wind vector, force fields) and of one step slot.
inline constexpr uint32_t kInstanceWindScalars = 4 * HMSM_INSTANCE_WIND_VEC4S;
inline constexpr uint32_t kWindHeaderScalars = 4 * HMSM_WIND_STEPS;
inline constexpr uint32_t kWindStepScalars = 4 * HMSM_WIND_STEP_VEC4S;

/// The wind clock: tau_n = tau_b + (f dt) (n - n_b), with (n_b, tau_b) moved to the step before
/// which the wind was last set, so tau stays continuous when f changes; f is the clock's rate,
/// wind_clock_rate (atmospheric: the mean wind speed, so tau is in metres).
struct WindClock {
    uint64_t base_step = 1;  ///< n_b
    double base_tau = 0.0;   ///< tau_b
    double tau(double frequency, double dt, uint64_t step) const {
        return base_tau + (frequency * dt) * double(step - base_step);
    }
    /// The clock at which step n samples the wind: tau_n, the step's start, under the paper's
    /// dynamics; the step's midpoint tau_n + f dt / 2 under `coupled` (docs/model.md 3.5).
    double sample(double frequency, double dt, uint64_t step, bool midpoint) const {
        return tau(frequency, dt, step) + (midpoint ? 0.5 * frequency * dt : 0.0);
    }
};

/// The mode constants of a wind setting's turbulent and atmospheric profiles (its turbulence
/// and seed), computed once per setting.
struct WindModes {
    TurbulentModes turbulent;
    AtmosphericModes atmospheric;
};
WindModes wind_modes(const Wind& wind);

/// The instance's wind phase phi = p + (v > 0 ? -f (o.d)/v : 0), d normalized.
double instance_wind_phase(const Wind& wind, const Instance& instance);

/// instance_wind element of `instance`: (lambda, phi mod 2, paused, fade word), then frac(m_k phi)
/// (atmospheric: the spatial phases, gpu_layout.h).
void fill_instance_wind(const Wind& wind, const WindModes& modes, const Instance& instance, double fade_word,
                        double* out);
/// Wind table header: amplitudes a_k, (s d, field count), s e_y and s e_z, the force fields.
/// `step_span` is the clock's advance over one step when each turbulent or atmospheric mode is
/// averaged over the step (`coupled`: f dt; a_k then carries the factor sinc), 0 where the
/// wind is sampled (docs/model.md 3.5).
void fill_wind_header(const Wind& wind, const WindModes& modes, std::span<const ForceField> fields,
                      double step_span, double* out);
/// The factor sin(pi c) / (pi c) by which the mean of a cosine of c cycles per step over the step
/// is smaller than its value at the step's midpoint.
double step_mean_factor(double cycles_per_step);
/// One step slot: (tau mod 2, 0, 0, 0), then frac(m_k tau + u_k) (atmospheric: kx_k for m_k).
void fill_wind_step(const Wind& wind, const WindModes& modes, double tau, double* out);

}  // namespace hmsm::detail
