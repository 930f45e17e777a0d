// Model options, physical parameters and wind (docs/model.md 3.2, 3.4, 3.5, 3.8).
#pragma once

#include <hmsm/export.h>

#include <hmsm/names.h>
#include <hmsm/status.h>

#include <hmsm/types.h>

#include <cstdint>
#include <optional>
#include <string_view>

namespace hmsm {

/// How a node picks the child that continues its chain (docs/model.md 3.2).
enum class Grouping { direction, width };
inline constexpr NamedValue<Grouping> kGroupingNames[] = {{Grouping::direction, "direction"},
                                                          {Grouping::width, "width"}};

/// The equations of motion (docs/model.md 3.7 for `paper`, 3.13 for `coupled`): the paper's
/// independent per-chain oscillators with free constants k and rho, or chains whose inertia,
/// stiffness and wind load come from the wood and leaves they carry, coupled to their parent
/// and children through their joints.
enum class Dynamics : uint32_t { paper = 0, coupled = 1 };
inline constexpr NamedValue<Dynamics> kDynamicsNames[] = {{Dynamics::paper, "paper"},
                                                          {Dynamics::coupled, "coupled"}};

/// How the coupled dynamics' chains exchange loads (docs/model.md 3.13): `held`, each chain takes
/// its children's loads of the last step, one gather per step with the children's inertia lumped
/// rigidly (every backend); or `articulated`, the joints of the whole tree solved together within
/// each step, two sweeps over the hierarchy, so that a branch's motion loads and detunes its
/// parent (every backend). Refused under `paper`.
enum class Exchange : uint32_t { held = 0, articulated = 1 };
inline constexpr NamedValue<Exchange> kExchangeNames[] = {{Exchange::held, "held"},
                                                          {Exchange::articulated, "articulated"}};

/// Options that shape the hierarchy and the branch mesh.
struct ModelOptions {
    Grouping grouping = Grouping::direction;
    int32_t max_chain_segments = 0;  ///< cut chains after this many nodes; 0 = never (the paper)
    int32_t ring_sides = 8;          ///< vertices per branch-mesh ring, >= 3
    double fix_weight = 0.5;         ///< contour fix-up weight beta in [0, 1]
    Dynamics dynamics = Dynamics::paper;
    Exchange exchange = Exchange::held;  ///< Dynamics::coupled only
};

/// Wood of the coupled dynamics (docs/model.md 3.13); the defaults are green broadleaf wood.
struct Material {
    double modulus = 9.0e9;  ///< E, Young's modulus along the grain (Pa)
    double density = 900.0;  ///< green density (kg/m^3)
};

/// Leaf cards in the coupled dynamics (docs/model.md 3.13): each card adds mass and drag in
/// proportion to its area (width x height).
struct Foliage {
    bool on = true;                 ///< leaf-on; leaf-off cards add nothing
    double mass_per_area = 0.2;     ///< fresh leaf mass per card area (kg/m^2)
    double drag_coefficient = 0.3;  ///< drag area per card area
};

/// Physical parameters (docs/model.md 3.4); defaults give natural sway at real-world tree sizes.
struct Parameters {
    double density = 1.0;         ///< rho
    double stiffness = 1.0e7;     ///< k
    double damping_ratio = 0.1;   ///< zeta
    double wind_gain = 0.2;       ///< gamma: strength 1 is a moderate breeze (docs/model.md 3.4)
    double max_angle = 0.8;       ///< theta_max (rad)
    double dt = 1.0 / 120.0;      ///< fixed time step (s)
    double max_frequency = 4.0;   ///< f_cap (Hz): no chain sways faster than this
    // The coupled dynamics (docs/model.md 3.13) takes dt, max_angle and these; it ignores
    // density, stiffness, damping_ratio, wind_gain and max_frequency.
    Material material;
    Foliage foliage;
    double structural_damping = 0.03;    ///< zeta_s: damping ratio of the wood alone
    double wood_drag_coefficient = 1.2;  ///< C_d of a branch segment (a cylinder across the flow)
};

/// The paper's four wind profiles, constant (Y = 1), none (Y = 0), turbulent (a sum of 32
/// modes with a von Karman-like spectrum) and atmospheric (a three-component Kaimal wind field
/// advected with the mean wind), docs/model.md 3.5.
enum class WindProfile : uint32_t {
    none = 0, constant = 1, y1 = 2, y2 = 3, y3 = 4, y4 = 5, turbulent = 6, atmospheric = 7
};
inline constexpr NamedValue<WindProfile> kWindProfileNames[] = {
    {WindProfile::none, "none"}, {WindProfile::constant, "constant"}, {WindProfile::y1, "y1"},
    {WindProfile::y2, "y2"},     {WindProfile::y3, "y3"},             {WindProfile::y4, "y4"},
    {WindProfile::turbulent, "turbulent"},
    {WindProfile::atmospheric, "atmospheric"},
};

struct Wind {
    WindProfile profile = WindProfile::y1;
    Vec3 direction{1.0, 0.0, 0.0};  ///< normalized when used; must be non-zero
    /// Dynamic pressure relative to a 6 m/s breeze: a wind of U m/s is strength (U / 6)^2
    /// (wind_strength_for_speed).
    double strength = 1.0;
    double frequency = 0.1;    ///< f (Hz): the rate of the profile's clock (atmospheric: unused)
    double front_speed = 0.0;  ///< v (m/s) > 0: a front travelling along direction; 0: none (atmospheric: unused)
    double turbulence = 0.3;   ///< sigma in [0, 2]: relative fluctuation of the turbulent and atmospheric profiles
    uint64_t seed = 0;         ///< the random modes of the turbulent and atmospheric profiles
};

/// Wind strength of a wind speed U in m/s: (U / 6)^2.
HMSM_API double wind_strength_for_speed(double speed);

/// Modes of the turbulent profile (docs/model.md 3.5).
inline constexpr uint32_t kTurbulentModes = 32;

/// The constants of the turbulent profile for one wind setting, in double: mode k contributes
/// a_k cos(2 pi (m_k x + u_k)) to Yt(x) = 1 + sum_k.
struct TurbulentModes {
    double multiple[kTurbulentModes];   ///< m_k = 2^((k - 8) / 4)
    double amplitude[kTurbulentModes];  ///< a_k = sigma sqrt(2) b_k / sqrt(sum b_j^2)
    double phase[kTurbulentModes];      ///< u_k = (splitmix64(seed + k) >> 11) 2^-53
};
HMSM_API TurbulentModes turbulent_modes(double turbulence, uint64_t seed);

/// Modes of the atmospheric profile per component: along the mean wind (u), lateral (v) and
/// vertical (w); mode k belongs to u for k < 16, v for 16 <= k < 24, w above (docs/model.md 3.5).
inline constexpr uint32_t kAtmosphericModesU = 16, kAtmosphericModesV = 8, kAtmosphericModesW = 8;

/// The constants of the atmospheric profile for one wind setting, in double: mode k contributes
/// a_k cos(2 pi (kx_k (xi - x.e_x) - ky_k x.e_y - kz_k x.e_z + u_k + q_k(xi))) to its component,
/// with xi the distance the mean wind has travelled, x the point and q_k the mode's wander, which
/// spreads its line over its band (docs/model.md 3.5).
struct AtmosphericModes {
    double wavenumber[kTurbulentModes];  ///< kx_k (cycles per metre) along the mean wind
    double lateral[kTurbulentModes];     ///< ky_k: Davenport-like lateral coherence
    double vertical[kTurbulentModes];    ///< kz_k: the same vertically
    double amplitude[kTurbulentModes];   ///< a_k, the Kaimal variance of the mode's band
    double phase[kTurbulentModes];       ///< u_k in [0, 1)
    /// Delta_k (m): the wander's knots lie Delta_k apart in xi, the inverse of the band's width.
    double wander_spacing[kTurbulentModes];
    uint64_t wander_key[kTurbulentModes];  ///< splitmix64(seed + 128 + k): the knots' values
};
HMSM_API AtmosphericModes atmospheric_modes(double turbulence, uint64_t seed);

/// The unit vectors of the atmospheric profile's components for a wind direction d: e_x =
/// unit(d), e_y = unit(e_up x e_x) with e_up = +y (+x where d is vertical), e_z = e_x x e_y.
struct WindFrame {
    Vec3 along, lateral, vertical;
};
HMSM_API WindFrame wind_frame(const Vec3& direction);

/// The rate of the wind clock (docs/model.md 3.5): the frequency f, or for `atmospheric` the
/// mean wind speed 6 sqrt(|s|) in m/s, so that the clock is the distance the wind has travelled.
HMSM_API double wind_clock_rate(const Wind& wind);

/// SplitMix64's output function (all arithmetic mod 2^64), as docs/model.md 3.5 uses it.
HMSM_API uint64_t splitmix64(uint64_t x);

/// Y(x) of docs/model.md 3.5 for the periodic profiles (none, constant, Y1-Y4; period 2);
/// `turbulent` needs the wind's modes: use wind_value.
HMSM_API double wind_profile_value(WindProfile profile, double x);
/// Y(x) of the wind's profile, the turbulent one included; for `atmospheric` 1 + u' at the
/// origin, x the clock in metres travelled.
HMSM_API double wind_value(const Wind& wind, double x);
/// w for an instance at `origin` with the wind fixed since the start: s Y(f t + phi) d, with
/// the instance's wind phase p and wind scale lambda (docs/model.md 3.5); for `atmospheric`
/// lambda s (e_x (1 + u') + e_y v' + e_z w') at the clock U t + p. (A step of the coupled
/// dynamics takes this wind's mean over the step, docs/model.md 3.5.)
HMSM_API Vec3 wind_at(const Wind& wind, const Vec3& origin, double t, double instance_phase = 0.0,
             double instance_scale = 1.0);
/// Front phase of an instance at `origin`: -f (o.d)/v with d normalized, or 0 without a front
/// (the instance's own wind phase p is added to it).
HMSM_API double wind_phase(const Wind& wind, const Vec3& origin);

HMSM_API const char* to_string(Grouping grouping);
HMSM_API const char* to_string(Dynamics dynamics);
HMSM_API std::optional<Dynamics> parse_dynamics(std::string_view name);
HMSM_API const char* to_string(Exchange exchange);
HMSM_API std::optional<Exchange> parse_exchange(std::string_view name);
HMSM_API const char* to_string(WindProfile profile);
HMSM_API std::optional<Grouping> parse_grouping(std::string_view name);
HMSM_API std::optional<WindProfile> parse_wind_profile(std::string_view name);

/// Valid ranges of docs/model.md 3.4; messages name the option.
HMSM_API Status validate(const ModelOptions& options);
HMSM_API Status validate(const Parameters& parameters);
HMSM_API Status validate(const Wind& wind);

}  // namespace hmsm
