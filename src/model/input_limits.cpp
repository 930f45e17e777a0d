#include "input_limits.h"

#include "json_util.h"

#include <cmath>
#include <cstdio>

namespace hmsm::detail {

namespace {

SizeLimits g_size_limits = kDefaultSizeLimits;

/// "<what> = <value> is out of range: <rule>", or "is not finite" for inf and NaN.
Status bad(std::string_view what, const std::string& value, const std::string& rule, bool finite = true) {
    return {ErrorCode::invalid_argument,
            std::string(what) + " = " + value + (finite ? " is out of range: " : " is not finite: ") + rule};
}

bool finite3(const glm::dvec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

std::string vec_text(const glm::dvec3& v) {
    return "(" + number_text(v.x) + ", " + number_text(v.y) + ", " + number_text(v.z) + ")";
}

}  // namespace

const SizeLimits& size_limits() { return g_size_limits; }

ScopedSizeLimits::ScopedSizeLimits(const SizeLimits& limits) : saved_(g_size_limits) { g_size_limits = limits; }
ScopedSizeLimits::~ScopedSizeLimits() { g_size_limits = saved_; }

uint64_t model_build_bytes(uint64_t nodes, uint64_t leaves, uint32_t ring_sides) {
    // Per node: the tree and hierarchy records and their scratch, plus a ring of `ring_sides`
    // mesh vertices with about two vertices' worth each of skin, template and flattened data
    // (320 bytes a vertex); per leaf four vertices and two triangles, counted twice as well. An
    // upper estimate: above the peak memory measured for simulations of the generator's trees.
    const uint64_t per_vertex = 320;
    return nodes * (2560 + uint64_t(ring_sides) * 2 * per_vertex) + leaves * (8 * per_vertex + 128);
}

std::string number_text(double value) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.6g", value);
    return buf;
}

std::string quote_input(std::string_view text) {
    constexpr size_t kShown = 80;
    std::string out;
    size_t used = 0;
    for (unsigned char ch : text) {
        if (out.size() >= kShown) break;
        ++used;
        append_escaped(out, ch);
    }
    if (used < text.size()) out += "... (" + std::to_string(text.size()) + " bytes)";
    return out;
}

Status check_coordinate(std::string_view what, const glm::dvec3& p) {
    for (int k = 0; k < 3; ++k)
        if (!(std::abs(p[k]) <= kMaxCoordinate))
            return bad(what, vec_text(p), "every coordinate must be finite and within +-" +
                                              number_text(kMaxCoordinate) + " m", finite3(p));
    return {};
}

Status check_radius(std::string_view what, double radius) {
    if (!(radius > 0.0 && radius <= kMaxRadius))
        return bad(what, number_text(radius), "must be finite, > 0 and <= " + number_text(kMaxRadius) + " m",
                   std::isfinite(radius));
    return {};
}

namespace {

Status check_range(std::string_view what, double value, PhysicalRange range, const char* unit) {
    if (!(value >= range.min && value <= range.max))
        return bad(what, number_text(value),
                   "must be finite and within [" + number_text(range.min) + ", " + number_text(range.max) + "]" + unit,
                   std::isfinite(value));
    return {};
}

}  // namespace

Status check_material(const Parameters& p) {
    HMSM_TRY(check_range("material.modulus", p.material.modulus, kModulusRange, " Pa"));
    HMSM_TRY(check_range("material.density", p.material.density, kWoodDensityRange, " kg/m^3"));
    HMSM_TRY(check_range("foliage.mass_per_area", p.foliage.mass_per_area, kLeafMassPerAreaRange, " kg/m^2"));
    HMSM_TRY(check_range("foliage.drag_coefficient", p.foliage.drag_coefficient, kDragCoefficientRange, ""));
    HMSM_TRY(check_range("wood_drag_coefficient", p.wood_drag_coefficient, kDragCoefficientRange, ""));
    HMSM_TRY(check_range("structural_damping", p.structural_damping, kStructuralDampingRange, ""));
    return {};
}

Status check_tree_material(std::string_view where, std::string_view species, double modulus, double density) {
    const std::string w(where);
    HMSM_TRY(check_range(w + "modulus", modulus, kModulusRange, " Pa"));
    HMSM_TRY(check_range(w + "density", density, kWoodDensityRange, " kg/m^3"));
    if (species.size() > kMaxSpeciesNameBytes)
        return Status{ErrorCode::invalid_argument, w + "species: " + quote_input(species) + " is longer than " +
                                                       std::to_string(kMaxSpeciesNameBytes) + " bytes"};
    return {};
}

Status check_force(std::string_view what, double value) {
    if (!(std::abs(value) <= kMaxForce))
        return bad(what, number_text(value), "must be finite and within +-" + number_text(kMaxForce),
                   std::isfinite(value));
    return {};
}

Status check_force(std::string_view what, const glm::dvec3& value) {
    for (int k = 0; k < 3; ++k)
        if (!(std::abs(value[k]) <= kMaxForce))
            return bad(what, vec_text(value), "every component must be finite and within +-" + number_text(kMaxForce),
                       finite3(value));
    return {};
}

Status check_wind_force(std::string_view what, double strength, double wind_scale, double area) {
    const double force = std::abs(strength) * wind_scale * area;
    if (!(force <= kMaxForce))
        return {ErrorCode::invalid_argument,
                std::string(what) + ": wind force A*|s|*lambda = " + number_text(area) + " * " +
                    number_text(std::abs(strength)) + " * " + number_text(wind_scale) + " = " + number_text(force) +
                    " is out of range: must be <= " + number_text(kMaxForce)};
    return {};
}

Status check_wind_scale(std::string_view what, double wind_scale) {
    if (!(wind_scale >= 0.0 && wind_scale <= kMaxWindScale))
        return bad(what, number_text(wind_scale), "must be finite, >= 0 and <= " + number_text(kMaxWindScale),
                   std::isfinite(wind_scale));
    return {};
}

Status check_wind_frequency(double frequency) {
    if (!(frequency >= 0.0 && frequency <= kMaxWindFrequency))
        return bad("wind frequency", number_text(frequency),
                   "must be finite, >= 0 and <= " + number_text(kMaxWindFrequency) + " Hz", std::isfinite(frequency));
    return {};
}

Status check_wind_clock(double frequency, double seconds, double phase) {
    if (!(std::abs(phase) <= kMaxWindPhase))
        return {ErrorCode::invalid_argument,
                "wind clock = " + number_text(phase) + " (rate " + number_text(frequency) + " per second, time " +
                    number_text(seconds) + " s) is out of range: it must stay within +-" +
                    number_text(kMaxWindPhase)};
    return {};
}

Status check_force_field(std::string_view what, const glm::dvec3& center, double radius,
                         const glm::dvec3& directional, double radial) {
    const std::string name(what);
    HMSM_TRY(check_coordinate(name + ": center", center));
    HMSM_TRY(check_radius(name + ": radius", radius));
    HMSM_TRY(check_force(name + ": directional", directional));
    return check_force(name + ": radial", radial);
}

Status check_count(std::string_view what, uint64_t count, uint64_t limit, ErrorCode code) {
    if (count > limit)
        return {code, std::string(what) + ": " + std::to_string(count) + " is more than the limit of " +
                          std::to_string(limit) + " (docs/model.md 3.11)"};
    return {};
}

}  // namespace hmsm::detail
