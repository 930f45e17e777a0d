// Model options, physical parameters and wind (docs/model.md 3.2, 3.4, 3.5, 3.8).
#pragma once

#include <hmsm/status.h>

#include <glm/vec3.hpp>

#include <cstdint>
#include <optional>
#include <string_view>

namespace hmsm {

/// How a node picks the child that continues its chain (docs/model.md 3.2).
enum class Grouping { direction, width };

/// Options that shape the hierarchy and the branch mesh.
struct ModelOptions {
    Grouping grouping = Grouping::direction;
    int32_t max_chain_segments = 0;  ///< cut chains after this many nodes; 0 = never (the paper)
    int32_t ring_sides = 8;          ///< vertices per branch-mesh ring, >= 3
    double fix_weight = 0.5;         ///< contour fix-up weight beta in [0, 1]
};

/// Physical parameters (docs/model.md 3.4); defaults give natural sway at real-world tree sizes.
struct Parameters {
    double density = 1.0;         ///< rho
    double stiffness = 1.0e7;     ///< k
    double damping_ratio = 0.1;   ///< zeta
    double wind_gain = 15.0;      ///< gamma
    double max_angle = 0.8;       ///< theta_max (rad)
    double dt = 1.0 / 120.0;      ///< fixed time step (s)
};

/// The paper's four wind profiles plus constant (Y = 1) and none (Y = 0).
enum class WindProfile : uint32_t { none = 0, constant = 1, y1 = 2, y2 = 3, y3 = 4, y4 = 5 };

struct Wind {
    WindProfile profile = WindProfile::y1;
    glm::dvec3 direction{1.0, 0.0, 0.0};  ///< normalized when used; must be non-zero
    double strength = 1.0;
    double frequency = 0.1;    ///< f: the profile is evaluated at f*t + phase
    double front_speed = 0.0;  ///< v > 0: a front travelling along direction; 0: none
};

/// Y(x) of docs/model.md 3.5.
double wind_profile_value(WindProfile profile, double x);
/// w(t) for an instance at `origin` (docs/model.md 3.5).
glm::dvec3 wind_at(const Wind& wind, const glm::dvec3& origin, double t);
/// Phase offset phi of an instance at `origin`: -f (o.d)/v, or 0 without a front.
double wind_phase(const Wind& wind, const glm::dvec3& origin);

const char* to_string(Grouping grouping);
const char* to_string(WindProfile profile);
std::optional<Grouping> parse_grouping(std::string_view name);
std::optional<WindProfile> parse_wind_profile(std::string_view name);

/// Valid ranges of docs/model.md 3.4; messages name the option.
Status validate(const ModelOptions& options);
Status validate(const Parameters& parameters);
Status validate(const Wind& wind);

}  // namespace hmsm
