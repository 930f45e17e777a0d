// Wind profiles (docs/model.md 3.5), option names and the valid ranges of options and parameters (docs/model.md 3.4).
#include <hmsm/options.h>

#include "../common/wind_profile.h"
#include "atmospheric_wind.h"
#include "input_limits.h"

#include <glm/geometric.hpp>

#include <cmath>
#include <numbers>
#include <string>

static_assert(uint32_t(hmsm::WindProfile::none) == HMSM_WIND_PROFILE_NONE);
static_assert(uint32_t(hmsm::WindProfile::constant) == HMSM_WIND_PROFILE_CONSTANT);
static_assert(uint32_t(hmsm::WindProfile::y1) == HMSM_WIND_PROFILE_Y1);
static_assert(uint32_t(hmsm::WindProfile::y2) == HMSM_WIND_PROFILE_Y2);
static_assert(uint32_t(hmsm::WindProfile::y3) == HMSM_WIND_PROFILE_Y3);
static_assert(uint32_t(hmsm::WindProfile::y4) == HMSM_WIND_PROFILE_Y4);
static_assert(uint32_t(hmsm::WindProfile::turbulent) == HMSM_WIND_PROFILE_TURBULENT);
static_assert(uint32_t(hmsm::WindProfile::atmospheric) == HMSM_WIND_PROFILE_ATMOSPHERIC);
static_assert(hmsm::kAtmosphericModesU + hmsm::kAtmosphericModesV + hmsm::kAtmosphericModesW == HMSM_WIND_MODES);
static_assert(hmsm::kAtmosphericModesU == 4 * HMSM_WIND_MODES_U_VEC4S &&
              hmsm::kAtmosphericModesV == 4 * HMSM_WIND_MODES_V_VEC4S);

namespace hmsm {

double wind_profile_value(WindProfile profile, double x) {
    return detail::wind_profile_y<double>(static_cast<unsigned>(profile), x);
}

uint64_t splitmix64(uint64_t x) {
    uint64_t z = x + 0x9E3779B97F4A7C15ull;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

TurbulentModes turbulent_modes(double turbulence, uint64_t seed) {
    // A von Karman-like spectrum sampled at 32 octave quarters from 0.25 to 54 times f: b_k is
    // the amplitude density sqrt(m S(m)) with S ~ (1 + m)^(-5/3); normalized so that the
    // fluctuation sum_k a_k cos(...) has variance sigma^2 (each cosine contributes a_k^2 / 2).
    TurbulentModes modes{};
    double norm = 0.0;
    double b[kTurbulentModes];
    for (uint32_t k = 0; k < kTurbulentModes; ++k) {
        const double m = std::pow(2.0, (double(k) - 8.0) / 4.0);
        modes.multiple[k] = m;
        b[k] = std::sqrt(m) * std::pow(1.0 + m, -5.0 / 6.0);
        norm += b[k] * b[k];
        modes.phase[k] = double(splitmix64(seed + k) >> 11) * 0x1.0p-53;
    }
    for (uint32_t k = 0; k < kTurbulentModes; ++k)
        modes.amplitude[k] = turbulence * std::sqrt(2.0) * b[k] / std::sqrt(norm);
    return modes;
}

double wind_value(const Wind& wind, double x) {
    if (wind.profile == WindProfile::atmospheric) {  // 1 + u' at the origin
        const AtmosphericModes modes = atmospheric_modes(wind.turbulence, wind.seed);
        return 1.0 + detail::atmospheric_component(modes, 0, kAtmosphericModesU, x, 0.0, glm::dvec3(0.0),
                                                   wind_frame(wind.direction));
    }
    if (wind.profile != WindProfile::turbulent) {
        return wind_profile_value(wind.profile, x - 2.0 * std::floor(x / 2.0));
    }
    const TurbulentModes modes = turbulent_modes(wind.turbulence, wind.seed);
    double y = 1.0;
    for (uint32_t k = 0; k < kTurbulentModes; ++k) {
        double phase = modes.multiple[k] * x + modes.phase[k];
        phase -= std::floor(phase);
        y += modes.amplitude[k] * std::cos(2.0 * std::numbers::pi * phase);
    }
    return y;
}

double wind_phase(const Wind& wind, const glm::dvec3& origin) {
    if (wind.front_speed <= 0.0 || wind.profile == WindProfile::atmospheric) return 0.0;
    return -wind.frequency * glm::dot(origin, glm::normalize(wind.direction)) / wind.front_speed;
}

double wind_strength_for_speed(double speed) { return (speed / 6.0) * (speed / 6.0); }

glm::dvec3 wind_at(const Wind& wind, const glm::dvec3& origin, double t, double instance_phase,
                   double instance_scale) {
    if (wind.profile == WindProfile::atmospheric) {
        const AtmosphericModes modes = atmospheric_modes(wind.turbulence, wind.seed);
        const WindFrame frame = wind_frame(wind.direction);
        const double clock = wind_clock_rate(wind) * t, p = instance_phase;
        const glm::dvec3 x = wind.strength < 0.0 ? -origin : origin;  // gusts travel with the mean wind
        const uint32_t v = kAtmosphericModesU, w = v + kAtmosphericModesV;
        const double u_rel = detail::atmospheric_component(modes, 0, v, clock, p, x, frame);
        const double v_rel = detail::atmospheric_component(modes, v, w, clock, p, x, frame);
        const double w_rel = detail::atmospheric_component(modes, w, kTurbulentModes, clock, p, x, frame);
        return instance_scale * wind.strength *
               ((1.0 + u_rel) * frame.along + v_rel * frame.lateral + w_rel * frame.vertical);
    }
    double y = wind_value(wind, wind.frequency * t + instance_phase + wind_phase(wind, origin));
    return instance_scale * wind.strength * y * glm::normalize(wind.direction);
}

const char* to_string(Grouping grouping) { return name_in(kGroupingNames, grouping); }
const char* to_string(Dynamics dynamics) { return name_in(kDynamicsNames, dynamics); }
std::optional<Dynamics> parse_dynamics(std::string_view name) { return value_named(kDynamicsNames, name); }
const char* to_string(Exchange exchange) { return name_in(kExchangeNames, exchange); }
std::optional<Exchange> parse_exchange(std::string_view name) { return value_named(kExchangeNames, name); }
const char* to_string(WindProfile profile) { return name_in(kWindProfileNames, profile); }
std::optional<Grouping> parse_grouping(std::string_view name) { return value_named(kGroupingNames, name); }
std::optional<WindProfile> parse_wind_profile(std::string_view name) {
    return value_named(kWindProfileNames, name);
}

namespace {

std::string number(double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.9g", v);
    return buf;
}

Status bad(const char* name, double value, const char* rule) {
    return {ErrorCode::invalid_argument,
            std::string(name) + " = " + number(value) + " is out of range: " + rule};
}

}  // namespace

Status validate(const ModelOptions& o) {
    if (o.ring_sides < 3) return bad("ring_sides", o.ring_sides, "must be >= 3");
    if (o.ring_sides > 1024) return bad("ring_sides", o.ring_sides, "must be <= 1024");
    if (!std::isfinite(o.fix_weight) || o.fix_weight < 0.0 || o.fix_weight > 1.0)
        return bad("fix_weight", o.fix_weight, "must be in [0, 1]");
    if (o.max_chain_segments < 0)
        return bad("max_chain_segments", o.max_chain_segments, "must be >= 0");
    if (o.dynamics != Dynamics::paper && o.dynamics != Dynamics::coupled)
        return {ErrorCode::invalid_argument,
                "dynamics " + std::to_string(static_cast<uint32_t>(o.dynamics)) + " does not exist"};
    if (o.exchange != Exchange::held && o.exchange != Exchange::articulated)
        return {ErrorCode::invalid_argument,
                "exchange " + std::to_string(static_cast<uint32_t>(o.exchange)) + " does not exist"};
    if (o.exchange == Exchange::articulated && o.dynamics != Dynamics::coupled)
        return {ErrorCode::invalid_argument, "exchange articulated needs dynamics coupled (the paper's chains "
                                             "exchange no loads)"};
    return {};
}

Status validate(const Parameters& p) {
    if (!std::isfinite(p.dt) || p.dt <= 0.0) return bad("dt", p.dt, "must be finite and > 0");
    if (!std::isfinite(p.density) || p.density <= 0.0)
        return bad("density", p.density, "must be finite and > 0");
    if (!std::isfinite(p.stiffness) || p.stiffness <= 0.0)
        return bad("stiffness", p.stiffness, "must be finite and > 0");
    if (!std::isfinite(p.damping_ratio) || p.damping_ratio < 0.0)
        return bad("damping_ratio", p.damping_ratio, "must be finite and >= 0");
    if (!std::isfinite(p.wind_gain) || p.wind_gain < 0.0)
        return bad("wind_gain", p.wind_gain, "must be finite and >= 0");
    if (!std::isfinite(p.max_angle) || p.max_angle <= 0.0 || p.max_angle > std::numbers::pi / 2)
        return bad("max_angle", p.max_angle, "must be in (0, pi/2]");
    if (!std::isfinite(p.max_frequency) || p.max_frequency <= 0.0)
        return bad("max_frequency", p.max_frequency, "must be finite and > 0");
    HMSM_TRY(detail::check_material(p));
    return {};
}

Status validate(const Wind& w) {
    HMSM_TRY(detail::check_force("wind strength", w.strength));
    HMSM_TRY(detail::check_wind_frequency(w.frequency));
    if (!std::isfinite(w.front_speed) || w.front_speed < 0.0)
        return bad("front speed", w.front_speed, "must be finite and >= 0");
    if (w.front_speed > 0.0 && w.front_speed < 0.01)
        return bad("front speed", w.front_speed, "must be 0 (no front) or >= 0.01 m/s");
    if (!std::isfinite(w.turbulence) || w.turbulence < 0.0 || w.turbulence > 2.0)
        return bad("turbulence", w.turbulence, "must be in [0, 2]");
    if (static_cast<uint32_t>(w.profile) > static_cast<uint32_t>(WindProfile::atmospheric))
        return {ErrorCode::invalid_argument, "wind profile " + std::to_string(static_cast<uint32_t>(w.profile)) +
                                                 " does not exist"};
    for (int i = 0; i < 3; ++i)
        if (!std::isfinite(w.direction[i]))
            return bad("wind direction component", w.direction[i], "must be finite");
    double len = glm::length(w.direction);
    if (!(len > 1e-12) || !std::isfinite(len))
        return {ErrorCode::invalid_argument, "wind direction must be non-zero"};
    return {};
}

}  // namespace hmsm
