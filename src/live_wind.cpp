#include "live_wind.h"

#include "model/atmospheric_wind.h"

#include <glm/geometric.hpp>

#include <cmath>
#include <numbers>

namespace hmsm::detail {
namespace {

double mod2(double x) { return x - 2.0 * std::floor(x / 2.0); }
double frac(double x) { return x - std::floor(x); }

/// The point whose spatial phases an instance at `origin` takes: gusts travel along the mean
/// wind, which blows against d for a negative strength.
Vec3 advected_point(const Wind& wind, const Vec3& origin) { return wind.strength < 0.0 ? -origin : origin; }

}  // namespace

WindModes wind_modes(const Wind& wind) {
    return {turbulent_modes(wind.turbulence, wind.seed), atmospheric_modes(wind.turbulence, wind.seed)};
}

double instance_wind_phase(const Wind& wind, const Instance& instance) {
    return instance.wind_phase + wind_phase(wind, instance.origin);
}

void fill_instance_wind(const Wind& wind, const WindModes& modes, const Instance& instance, double fade_word,
                        double* out) {
    const double phi = instance_wind_phase(wind, instance);
    out[0] = instance.wind_scale;
    out[1] = mod2(phi);
    out[2] = instance.active ? 0.0 : 1.0;  // paused (gpu_layout.h)
    out[3] = fade_word;  // gpu_layout.h HMSM_FADE_*
    if (wind.profile == WindProfile::atmospheric) {
        const WindFrame frame = wind_frame(wind.direction);
        const Vec3 x = advected_point(wind, instance.origin);
        for (uint32_t k = 0; k < kTurbulentModes; ++k)
            out[4 + k] = atmospheric_instance_phase(modes.atmospheric, k, phi, x, frame);
        return;
    }
    for (uint32_t k = 0; k < kTurbulentModes; ++k)
        out[4 + k] = wind.profile == WindProfile::turbulent ? frac(modes.turbulent.multiple[k] * phi) : 0.0;
}

double step_mean_factor(double cycles_per_step) {
    const double x = std::numbers::pi * cycles_per_step;
    return x == 0.0 ? 1.0 : std::sin(x) / x;
}

void fill_wind_header(const Wind& wind, const WindModes& modes, std::span<const ForceField> fields,
                      double step_span, double* out) {
    for (uint32_t i = 0; i < kWindHeaderScalars; ++i) out[i] = 0.0;
    const bool atmospheric = wind.profile == WindProfile::atmospheric;
    for (uint32_t k = 0; k < kTurbulentModes; ++k) {
        // A mode's cycles per unit of the clock: kx_k (per metre of travel) or m_k.
        const double rate = atmospheric ? modes.atmospheric.wavenumber[k] : modes.turbulent.multiple[k];
        const double amplitude = atmospheric ? modes.atmospheric.amplitude[k] : modes.turbulent.amplitude[k];
        out[4 * HMSM_WIND_AMPLITUDES + k] = amplitude * step_mean_factor(rate * step_span);
    }
    const Vec3 w = wind.strength * glm::normalize(wind.direction);
    double* vector = out + 4 * HMSM_WIND_VECTOR;
    vector[0] = w.x;
    vector[1] = w.y;
    vector[2] = w.z;
    vector[3] = double(fields.size());
    if (atmospheric) {
        const WindFrame frame = wind_frame(wind.direction);
        for (int i = 0; i < 3; ++i) {
            out[4 * HMSM_WIND_LATERAL + i] = wind.strength * frame.lateral[i];
            out[4 * HMSM_WIND_VERTICAL + i] = wind.strength * frame.vertical[i];
        }
    }
    for (size_t f = 0; f < fields.size(); ++f) {
        double* sphere = out + 4 * (HMSM_WIND_FIELDS + 2 * f);
        double* force = sphere + 4;
        const ForceField& field = fields[f];
        sphere[0] = field.center.x;
        sphere[1] = field.center.y;
        sphere[2] = field.center.z;
        sphere[3] = field.radius;
        if (field.kind == ForceField::Kind::directional) {
            force[0] = field.directional.x;
            force[1] = field.directional.y;
            force[2] = field.directional.z;
            force[3] = 0.0;
        } else {
            force[0] = field.radial;
            force[1] = force[2] = 0.0;
            force[3] = 1.0;
        }
    }
}

void fill_wind_step(const Wind& wind, const WindModes& modes, double tau, double* out) {
    out[0] = mod2(tau);
    out[1] = out[2] = out[3] = 0.0;  // out[1]: the step's load half, set by the caller (gpu_layout.h)
    for (uint32_t k = 0; k < kTurbulentModes; ++k) {
        if (wind.profile == WindProfile::atmospheric)
            out[4 + k] = atmospheric_step_phase(modes.atmospheric, k, tau);
        else
            out[4 + k] = wind.profile == WindProfile::turbulent
                             ? frac(modes.turbulent.multiple[k] * tau + modes.turbulent.phase[k])
                             : 0.0;
    }
}

}  // namespace hmsm::detail
