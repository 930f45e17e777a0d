// The atmospheric wind profile (docs/model.md 3.5): a Kaimal spectrum per component (IEC
// 61400-1 Ed. 3, Annex B), realised with one mode per log-spaced wavenumber band at a seeded
// wavenumber within the band, Taylor-advected with the mean wind, its phase wandering so that
// its line spreads over the band, with seeded lateral and vertical wavenumbers that give
// Davenport-like coherence.
#include "atmospheric_wind.h"

#include <glm/geometric.hpp>

#include <cmath>
#include <numbers>

namespace hmsm {
namespace {

// Integral length scales of the Kaimal spectra (IEC 61400-1 Ed. 3, Table B.1) at the reference
// height 10 m: Lambda = 0.7 z, L_u = 8.1 Lambda, L_v = 2.7 Lambda, L_w = 0.66 Lambda.
constexpr double kScaleParameter = 0.7 * 10.0;
constexpr double kLengthScale[3] = {8.1 * kScaleParameter, 2.7 * kScaleParameter, 0.66 * kScaleParameter};
// Standard deviations of u', v', w' relative to sigma: sigma_v = 0.8 sigma_u, sigma_w = 0.5
// sigma_u (IEC 61400-1 Ed. 3, B.2), and the quasi-steady force |V| V ~ U^2 (e_x (1 + 2 u/U) +
// e_y v/U + e_z w/U): u' = 2 u/U carries sigma, v' = v/U and w' = w/U half the intensity ratio.
constexpr double kRelativeDeviation[3] = {1.0, 0.8 / 2.0, 0.5 / 2.0};
// Wavenumber bands (cycles per metre): from 0.02 / L (the spectrum's low end) to 4 (a 24 Hz
// gust at 6 m/s); the variance outside is left out and the rest scaled to the full variance.
constexpr double kLowestBand = 0.02;
constexpr double kHighestWavenumber = 4.0;
// The wander's knot values are uniform in [-kWanderAmplitude, kWanderAmplitude] cycles.
constexpr double kWanderAmplitude = 0.5;
// Davenport-like decay of the coherence exp(-c f r / U) across the wind (IEC 61400-1 Ed. 3,
// B.2 uses c = 12 for the exponential coherence model).
constexpr double kCoherenceDecay = 12.0;

constexpr uint32_t kFirst[4] = {0, kAtmosphericModesU, kAtmosphericModesU + kAtmosphericModesV, kTurbulentModes};

/// Uniform in (0, 1) from draw j of mode k: the top 53 bits of splitmix64(seed + 32 j + k), at
/// the midpoint of their interval.
double uniform_open(uint64_t seed, uint32_t j, uint32_t k) {
    return (double(splitmix64(seed + 32u * j + k) >> 11) + 0.5) * 0x1.0p-53;
}

/// The Kaimal variance below wavenumber kappa, relative to the total: 1 - (1 + 6 kappa L)^(-2/3).
double kaimal_below(double kappa, double length) { return 1.0 - std::pow(1.0 + 6.0 * kappa * length, -2.0 / 3.0); }

}  // namespace

AtmosphericModes atmospheric_modes(double turbulence, uint64_t seed) {
    AtmosphericModes modes{};
    for (uint32_t c = 0; c < 3; ++c) {
        const double length = kLengthScale[c];
        const uint32_t first = kFirst[c], count = kFirst[c + 1] - kFirst[c];
        const double low = kLowestBand / length, ratio = std::pow(kHighestWavenumber / low, 1.0 / count);
        double band_variance[kTurbulentModes], total = 0.0;
        for (uint32_t j = 0; j < count; ++j) {
            const uint32_t k = first + j;
            const double edge = low * std::pow(ratio, double(j));
            band_variance[j] = kaimal_below(edge * ratio, length) - kaimal_below(edge, length);
            total += band_variance[j];
            // A wavenumber uniform in log within the band, so the modes form no lattice.
            modes.wavenumber[k] = edge * std::pow(ratio, uniform_open(seed, 1, k));
            // Cauchy-distributed cross-wind wavenumbers of scale c kx / (2 pi): the mean of
            // cos(2 pi ky r) over the modes of a band is exp(-c kx r) = exp(-c f r / U).
            const double scale = kCoherenceDecay * modes.wavenumber[k] / (2.0 * std::numbers::pi);
            modes.lateral[k] = scale * std::tan(std::numbers::pi * (uniform_open(seed, 2, k) - 0.5));
            modes.vertical[k] = scale * std::tan(std::numbers::pi * (uniform_open(seed, 3, k) - 0.5));
            modes.phase[k] = double(splitmix64(seed + k) >> 11) * 0x1.0p-53;
            modes.wander_spacing[k] = 1.0 / (edge * (ratio - 1.0));
            modes.wander_key[k] = splitmix64(seed + 4u * 32u + k);
        }
        const double deviation = turbulence * kRelativeDeviation[c];
        for (uint32_t j = 0; j < count; ++j)
            modes.amplitude[first + j] = deviation * std::sqrt(2.0 * band_variance[j] / total);
    }
    return modes;
}

WindFrame wind_frame(const Vec3& direction) {
    WindFrame frame;
    frame.along = glm::normalize(direction);
    Vec3 lateral = glm::cross(Vec3(0.0, 1.0, 0.0), frame.along);
    if (glm::length(lateral) < 1e-6) lateral = glm::cross(Vec3(1.0, 0.0, 0.0), frame.along);  // d vertical
    frame.lateral = glm::normalize(lateral);
    frame.vertical = glm::cross(frame.along, frame.lateral);
    return frame;
}

double wind_clock_rate(const Wind& wind) {
    if (wind.profile == WindProfile::atmospheric) return 6.0 * std::sqrt(std::abs(wind.strength));
    return wind.frequency;
}

namespace detail {

double fraction(double x) { return x - std::floor(x); }

double atmospheric_wander(const AtmosphericModes& modes, uint32_t k, double clock) {
    const double at = clock / modes.wander_spacing[k], knot = std::floor(at);
    auto value = [&](double m) {
        const uint64_t bits = splitmix64(modes.wander_key[k] + uint64_t(int64_t(m)));
        return kWanderAmplitude * (2.0 * (double(bits >> 11) * 0x1.0p-53) - 1.0);
    };
    const double before = value(knot), after = value(knot + 1.0);
    return before + (at - knot) * (after - before);
}

double atmospheric_step_phase(const AtmosphericModes& modes, uint32_t k, double clock) {
    return fraction(fraction(modes.wavenumber[k] * clock + modes.phase[k]) + atmospheric_wander(modes, k, clock));
}

double atmospheric_instance_phase(const AtmosphericModes& modes, uint32_t k, double p, const Vec3& x,
                                  const WindFrame& frame) {
    const double along = fraction(modes.wavenumber[k] * (p - glm::dot(x, frame.along)));
    const double lateral = fraction(-modes.lateral[k] * glm::dot(x, frame.lateral));
    const double vertical = fraction(-modes.vertical[k] * glm::dot(x, frame.vertical));
    return fraction(along + lateral + vertical);
}

double atmospheric_component(const AtmosphericModes& modes, uint32_t begin, uint32_t end, double clock, double p,
                             const Vec3& x, const WindFrame& frame) {
    double sum = 0.0;
    for (uint32_t k = begin; k < end; ++k) {
        const double phase =
            fraction(atmospheric_step_phase(modes, k, clock) + atmospheric_instance_phase(modes, k, p, x, frame));
        sum += modes.amplitude[k] * std::cos(2.0 * std::numbers::pi * phase);
    }
    return sum;
}

}  // namespace detail
}  // namespace hmsm
