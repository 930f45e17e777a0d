// The numbers behind `hmsm analyze`: per-chain natural frequency and damping from the chain
// constants (docs/model.md 3.4), static deflection, and a top node's step response and sway
// spectrum measured from cpu64 simulation runs.
#pragma once

#include <hmsm/hmsm.h>

#include <complex>
#include <functional>
#include <string>
#include <vector>

namespace hmsm::cli {

struct AnalysisSettings {
    ModelOptions options;
    Parameters parameters;
    double wind_speed = 6.0;               ///< m/s: static deflection and step response
    glm::dvec3 wind_direction{1.0, 0.0, 0.0};
    double step_seconds = 30.0;
    Wind spectrum_wind;                    ///< strength set from wind_speed by the caller
    double spectrum_seconds = 60.0;
    std::function<void()> on_step;         ///< called after every simulated step (progress)
};

struct ChainAnalysis {
    int32_t chain = 0, parent = -1, depth = 0;
    double length = 0, radius = 0;
    double frequency_hz = 0;     ///< sqrt(K/I) / 2 pi with the library's I
    double damping_ratio = 0;    ///< D / (2 sqrt(K I))
    bool capped = false;         ///< the frequency cap raised I (docs/model.md 3.4)
    double static_angle = 0;     ///< A s / K, clamped to theta_max (rad)
    double static_tip_m = 0;     ///< the chain's tip displacement from its own bend, L sin(angle)
};

struct StepResponse {
    std::vector<double> time, deflection;  ///< top node displacement along the wind (m)
    double steady_m = 0;        ///< mean over the last quarter of the run
    double frequency_hz = 0;    ///< from the spacing of the oscillation's peaks; 0 if too few
    double damping_ratio = 0;   ///< from the peaks' exponential decay
    int peaks = 0;              ///< peaks used by the fit
};

struct Spectrum {
    std::vector<double> frequency_hz, power;  ///< one-sided PSD of the sway along the wind (m^2/Hz)
    double peak_hz = 0;                       ///< strongest frequency above 2 / duration
};

struct ModelAnalysis {
    std::string name;
    size_t nodes = 0;
    double height = 0;
    int32_t top_node = 0;  ///< highest rest y, lowest index on ties
    double wind_strength = 0;
    std::vector<ChainAnalysis> chains;
    StepResponse step;
    Spectrum spectrum;
};

/// Whether the cap raises chain `c`'s inertia, evaluated from docs/model.md 3.4's formula with
/// the raw I = rho r^2 L^3: an independent check of hmsm::Chain::capped (the analysis reports
/// the library's flag).
bool chain_capped(const Chain& chain, const Parameters& parameters);

/// Wind strength of a speed: s = (U / 6 m/s)^2 (docs/model.md 3.5).
inline double strength_of_speed(double speed) { return (speed / 6.0) * (speed / 6.0); }

Result<ModelAnalysis> analyze_model(const TreeModel& tree, const std::string& name,
                                    const AnalysisSettings& settings);

/// Peak-based fit of a damped oscillation about its final value (exposed for tests).
void fit_oscillation(StepResponse& response);

/// Damping ratio of a decay whose successive peaks (times t, amplitudes > 0) fall exponentially,
/// oscillating at frequency_hz: ln(a) = c - sigma t by least squares, zeta = sigma / |s|.
double decay_damping_ratio(const std::vector<double>& t, const std::vector<double>& amplitude, double frequency_hz);

/// One-sided power spectral density (m^2/Hz) of samples spaced dt, mean removed, Hann window,
/// zero-padded to a power of two; its peak is the strongest bin above min_peak_hz.
Spectrum power_spectrum(const std::vector<double>& x, double dt, double min_peak_hz);

/// In-place radix-2 FFT (forward, unnormalized); the size must be a power of two.
void fft(std::vector<std::complex<double>>& a);

}  // namespace hmsm::cli
