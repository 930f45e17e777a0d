// The limits of every input (docs/model.md 3.11): the ranges of the numbers that reach the
// float device state and the sizes of what a file or call may ask hmsm to build. Every entry
// point (API, C ABI, tree, forest, schedule, importers, CLI) checks through these functions, so
// a value is judged the same wherever it enters and the message names the value and the limit.
#pragma once

#include <hmsm/options.h>
#include <hmsm/status.h>

#include <glm/vec3.hpp>

#include <cstdint>
#include <string>
#include <string_view>

namespace hmsm::detail {

// --- Ranges. The float backends square distances and multiply a force by an area, a wind
// scale and a profile value: these bounds keep every such product far inside float range
// (about 3.4e38), so no input can turn a chain's state into inf or NaN.

/// |x|, |y|, |z| of tree node positions, instance origins and force-field centres (m).
inline constexpr double kMaxCoordinate = 1e9;
/// Tree node radii and force-field radii (m); a radius must also be > 0.
inline constexpr double kMaxRadius = 1e9;
/// Wind strength |s|, a force field's |F| (directional: each component; radial: the
/// strength) and the wind force A |s| lambda of every chain (A its wind area, lambda the
/// instance's wind scale).
inline constexpr double kMaxForce = 1e30;
/// An instance's wind scale lambda (>= 0).
inline constexpr double kMaxWindScale = 1e6;
/// The wind profile frequency f (>= 0), in profile periods per second.
inline constexpr double kMaxWindFrequency = 1e6;
/// The wind clock f t: beyond it the phase reduced mod 2 keeps no fractional digits.
inline constexpr double kMaxWindPhase = 1e15;

/// The coupled dynamics' wood and leaves (docs/model.md 3.13): every real wood lies far inside
/// these ranges (green wood: E of 5 to 20 GPa, density of 400 to 1,200 kg/m^3); values past
/// them are typing errors (E in GPa instead of Pa, density in g/cm^3).
struct PhysicalRange {
    double min, max;
};
inline constexpr PhysicalRange kModulusRange{1e7, 1e12};          ///< E (Pa)
inline constexpr PhysicalRange kWoodDensityRange{10.0, 1e4};      ///< kg/m^3
inline constexpr PhysicalRange kLeafMassPerAreaRange{0.0, 100.0}; ///< kg/m^2
inline constexpr PhysicalRange kDragCoefficientRange{0.0, 10.0};  ///< wood and leaves
inline constexpr PhysicalRange kStructuralDampingRange{0.0, 10.0};
/// A tree file's species name (docs/model.md 4.1): bytes.
inline constexpr size_t kMaxSpeciesNameBytes = 64;

// --- Sizes, checked from counts before anything proportional to them is allocated.

// Instances of one simulation: hmsm::kMaxInstances (include/hmsm/scene.h).

/// Size limits that tests may lower (ScopedSizeLimits); the defaults are documented.
struct SizeLimits {
    uint64_t input_bytes;      ///< a tree, forest, schedule or importer file (bytes)
    uint64_t tree_nodes;       ///< nodes of one tree (its chains are fewer)
    uint64_t tree_leaves;      ///< leaves of one tree
    uint64_t forest_models;    ///< models named by one forest file
    uint64_t schedule_events;  ///< events of one schedule
    uint64_t build_bytes;      ///< host memory the models of one simulation may take to build
};
inline constexpr SizeLimits kDefaultSizeLimits{
    uint64_t(256) << 20, 1'000'000, 10'000'000, 10'000, 1'000'000, uint64_t(8) << 30};
/// The limits in force (the defaults unless a test lowered them).
const SizeLimits& size_limits();

/// Test hook: lowers the size limits for its lifetime (not thread-safe; tests only).
class ScopedSizeLimits {
public:
    explicit ScopedSizeLimits(const SizeLimits& limits);
    ~ScopedSizeLimits();
    ScopedSizeLimits(const ScopedSizeLimits&) = delete;
    ScopedSizeLimits& operator=(const ScopedSizeLimits&) = delete;

private:
    SizeLimits saved_;
};

/// Host bytes building one model takes (hierarchy, mesh template and their scratch), sized from
/// its counts before the build: an upper estimate, measured on the generator's trees.
uint64_t model_build_bytes(uint64_t nodes, uint64_t leaves, uint32_t ring_sides);

// --- Checks. `what` names the value ("instance 3: origin"); the message adds the value and
// the limit. All return invalid_argument.

Status check_coordinate(std::string_view what, const glm::dvec3& position);
/// Finite, > 0 and <= kMaxRadius.
Status check_radius(std::string_view what, double radius);
/// Finite and |value| <= kMaxForce.
Status check_force(std::string_view what, double value);
Status check_force(std::string_view what, const glm::dvec3& value);
/// The product of a wind strength, a wind scale and a chain's wind area within kMaxForce.
Status check_wind_force(std::string_view what, double strength, double wind_scale, double area);
/// Finite, >= 0 and <= kMaxWindScale.
Status check_wind_scale(std::string_view what, double wind_scale);
/// Finite, >= 0 and <= kMaxWindFrequency.
Status check_wind_frequency(double frequency);
/// The wind clock `phase` (f t, continued across frequency changes) at simulated time
/// `seconds` within kMaxWindPhase.
Status check_wind_clock(double frequency, double seconds, double phase);
/// The material, foliage and damping of the coupled dynamics within the ranges above
/// ("material.modulus = 9 is out of range: must be finite and within [1e+07, 1e+12] Pa").
Status check_material(const Parameters& parameters);
/// A tree's material (modulus, density) within the ranges above and its species name within
/// kMaxSpeciesNameBytes; `where` prefixes the field ("material.modulus").
Status check_tree_material(std::string_view where, std::string_view species, double modulus, double density);
/// A force field (center, radius, force) within the ranges above.
Status check_force_field(std::string_view what, const glm::dvec3& center, double radius,
                         const glm::dvec3& directional, double radial);
/// `count` items of `what` within `limit` ("schedule: 2000001 events, at most 1000000").
Status check_count(std::string_view what, uint64_t count, uint64_t limit, ErrorCode code = ErrorCode::invalid_argument);

/// An input value for a message: control characters escaped and at most 80 characters, the
/// rest cut with "... (N bytes)". Every message that quotes a value taken from input uses it.
std::string quote_input(std::string_view text);
/// A double for a message, "%.6g".
std::string number_text(double value);

}  // namespace hmsm::detail
