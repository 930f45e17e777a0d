// The whole-tree numbers behind `hmsm analyze --whole-tree`, for either dynamics: the trunk top's
// free decay after a release test (natural frequency f0 and damping ratio), and its sway under the
// atmospheric wind at chosen speeds (spectrum slope above f0, cross-wind to along-wind ratio, mean
// base lean and mean top displacement relative to the height). Measured from cpu64 runs.
#pragma once

#include "analysis.h"

#include <hmsm/hmsm.h>

#include <array>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace hmsm::cli {

struct TreeResponseSettings {
    ModelOptions options;
    Parameters parameters;
    glm::dvec3 wind_direction{1.0, 0.0, 0.0};
    double pull_speed = 10.0;     ///< m/s of the constant wind that bends the tree before release
    double pull_seconds = 20.0;   ///< how long it pulls
    double release_seconds = 60.0;  ///< recorded free decay after the wind stops
    std::vector<double> sway_speeds{5.0, 10.0, 20.0};  ///< m/s of the atmospheric wind runs
    double sway_seconds = 120.0;  ///< recorded per speed, after the settling time
    double settle_seconds = 20.0; ///< wind on, not recorded (the start-up transient)
    double turbulence = 0.3;      ///< sigma of the atmospheric profile
    uint64_t seed = 0;
    std::function<void()> on_step;  ///< called after every simulated step (progress)
};

/// The trunk top's free decay after the pull: displacement along the wind from its rest position.
struct ReleaseTest {
    std::vector<double> time, displacement;
    double pulled_m = 0;          ///< displacement at the release
    double frequency_hz = 0;      ///< from the upward zero crossings (0 if fewer than 3)
    double fft_frequency_hz = 0;  ///< peak of the decay's spectrum, interpolated
    double damping_ratio = 0;     ///< from the decay of the peak per cycle (logarithmic decrement)
    int cycles = 0;               ///< cycles used by the fits
};

/// The trunk top under the atmospheric wind at one speed.
struct SwayRun {
    double speed = 0, strength = 0;
    Spectrum along;                  ///< PSD of the along-wind sway
    double band_low_hz = 0, band_high_hz = 0;  ///< the slope's band: 1.5 f0 ... min(10 f0, fs / 4)
    double slope = 0;                ///< d log PSD / d log f over the band (log-binned least squares)
    int band_bins = 0;               ///< log bins with power in the band (the slope needs >= 3)
    double mean_along_m = 0, rms_along_m = 0, rms_cross_m = 0;  ///< rms about the mean
    double cross_ratio = 0;          ///< rms_cross / rms_along
    double mean_lean_rad = 0;        ///< mean angle of the trunk's first segment from its rest direction
    double mean_top_over_height = 0; ///< |mean horizontal top displacement| / height
};

/// The coupled links linearized about the rest pose (docs/model.md 3.13, "The links
/// linearized"): the lowest modes of the whole tree with the joint-space mass matrix the dynamics
/// keeps only on its diagonal, the share of the tree's mass each moves along and across the wind,
/// the whole tree's sway from its static deflection, and the trunk chain's own f0 beside them.
struct LinkModesReport {
    std::vector<double> frequency_hz;
    std::vector<std::array<double, 2>> mass_share;  ///< (along, across) the wind
    std::array<double, 2> sway_hz{};                ///< along, across
    std::array<double, 2> trunk_f0_hz{};            ///< the trunk chain's axes x, z
    bool converged = false;
};

struct TreeResponse {
    std::string name;
    size_t nodes = 0;
    double height = 0;
    int32_t top_node = 0, base_node = 0;  ///< highest node; the first node above the root on its path
    double dbh = 0;  ///< diameter at breast height: 2 r at 1.3 m above the root on the root-top path
    ReleaseTest release;
    std::vector<SwayRun> sway;
    std::optional<LinkModesReport> links;  ///< Dynamics::coupled only
};

Result<TreeResponse> analyze_tree_response(const TreeModel& tree, const std::string& name,
                                           const TreeResponseSettings& settings);

/// The linearized links of `tree` under the settings' coupled dynamics: `modes` lowest modes,
/// the sway along and across the settings' wind direction.
Result<LinkModesReport> analyze_link_modes(const TreeModel& tree, const TreeResponseSettings& settings, int modes);

/// Frequency, damping and cycles of a free decay about zero (exposed for tests).
void fit_release(ReleaseTest& release, double dt);

/// Frequency (Hz) of a free decay about zero sampled every `dt`, from the release fit's upward
/// zero crossings (0 with fewer than 3).
double decay_frequency(const std::vector<double>& displacement, double dt);

/// Least-squares slope of log10 power against log10 frequency over [low, high], after averaging
/// the power in bins of 1/20 decade; `bins` receives the bins used. 0 with fewer than 3 bins.
double log_log_slope(const Spectrum& spectrum, double low, double high, int& bins);

}  // namespace hmsm::cli
