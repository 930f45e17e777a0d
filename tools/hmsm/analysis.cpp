// See analysis.h.
#include "analysis.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>

namespace hmsm::cli {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

/// Runs `seconds` of simulation and returns the top node's displacement along `along` per step.
Result<std::vector<double>> trace_top(const TreeModel& tree, int32_t top, const AnalysisSettings& s,
                                      const Wind& wind, double seconds, const glm::dvec3& along) {
    TreeModel bare = tree;
    // Under paper leaves do not act on the motion: skip their vertices. Under coupled they
    // carry mass and drag (docs/model.md 3.13) and stay.
    if (s.options.dynamics == Dynamics::paper) bare.leaves.clear();
    SimulationConfig config;
    config.backend = BackendKind::cpu64;
    config.model = s.options;
    config.model.ring_sides = 3;  // the mesh does not act on the motion either
    config.parameters = s.parameters;
    config.wind = wind;
    auto sim = Simulation::create(single_tree_scene(std::move(bare)), config);
    if (!sim) return sim.status();
    const uint64_t steps = uint64_t(std::ceil(seconds / s.parameters.dt));
    if (steps > 20'000'000) return Status{ErrorCode::invalid_argument, "analysis run too long: more than 2e7 steps"};
    const glm::dvec3 rest = tree.nodes[size_t(top)].position - tree.nodes[0].position;
    std::vector<double> out;
    out.reserve(steps);
    std::vector<double> xyz;
    for (uint64_t k = 0; k < steps; ++k) {
        HMSM_TRY((*sim)->step(1));
        if (s.on_step) s.on_step();
        HMSM_TRY((*sim)->read(Output::node_positions, xyz));
        const glm::dvec3 p(xyz[3 * size_t(top)], xyz[3 * size_t(top) + 1], xyz[3 * size_t(top) + 2]);
        out.push_back(glm::dot(p - rest, along));
    }
    return out;
}

}  // namespace

void fft(std::vector<std::complex<double>>& a) {
    const size_t n = a.size();
    for (size_t i = 1, j = 0; i < n; ++i) {
        size_t bit = n >> 1;
        for (; j & bit; bit >>= 1) j ^= bit;
        j ^= bit;
        if (i < j) std::swap(a[i], a[j]);
    }
    for (size_t len = 2; len <= n; len <<= 1) {
        const std::complex<double> w = std::polar(1.0, -kTwoPi / double(len));
        for (size_t i = 0; i < n; i += len) {
            std::complex<double> z = 1.0;
            for (size_t k = 0; k < len / 2; ++k, z *= w) {
                const auto u = a[i + k], v = a[i + k + len / 2] * z;
                a[i + k] = u + v;
                a[i + k + len / 2] = u - v;
            }
        }
    }
}

bool chain_capped(const Chain& chain, const Parameters& p) {
    const double raw_inertia = p.density * chain.radius * chain.radius * std::pow(chain.length, 3);
    const double f_max = std::min(p.max_frequency, 1.0 / (2.0 * kTwoPi * p.dt * std::max(1.0, p.damping_ratio)));
    return raw_inertia < chain.stiffness / ((kTwoPi * f_max) * (kTwoPi * f_max));
}

void fit_oscillation(StepResponse& r) {
    const size_t n = r.deflection.size();
    r.peaks = 0;
    r.frequency_hz = r.damping_ratio = 0;
    if (n < 8) return;
    double tail = 0;
    for (size_t i = n - n / 4; i < n; ++i) tail += r.deflection[i];
    r.steady_m = tail / double(n / 4);
    // Positive peaks of the deviation from the final value; stop once they sink into the noise.
    std::vector<double> t, amplitude;
    for (size_t i = 1; i + 1 < n; ++i) {
        const double e = r.deflection[i] - r.steady_m;
        if (e > 0 && e > r.deflection[i - 1] - r.steady_m && e >= r.deflection[i + 1] - r.steady_m) {
            if (!amplitude.empty() && e < 0.02 * amplitude.front()) break;
            t.push_back(r.time[i]);
            amplitude.push_back(e);
        }
    }
    if (t.size() < 2) return;
    r.peaks = int(t.size());
    r.frequency_hz = double(t.size() - 1) / (t.back() - t.front());
    r.damping_ratio = decay_damping_ratio(t, amplitude, r.frequency_hz);
}

double decay_damping_ratio(const std::vector<double>& t, const std::vector<double>& amplitude, double frequency_hz) {
    if (t.size() < 2 || t.size() != amplitude.size()) return 0.0;
    // ln(amplitude) = c - sigma t by least squares; zeta = sigma / sqrt(sigma^2 + omega_d^2).
    double mt = 0, ma = 0;
    for (size_t k = 0; k < t.size(); ++k) mt += t[k], ma += std::log(amplitude[k]);
    mt /= double(t.size()), ma /= double(t.size());
    double stt = 0, sta = 0;
    for (size_t k = 0; k < t.size(); ++k) {
        stt += (t[k] - mt) * (t[k] - mt);
        sta += (t[k] - mt) * (std::log(amplitude[k]) - ma);
    }
    const double sigma = stt > 0 ? -sta / stt : 0.0;
    const double omega = kTwoPi * frequency_hz;
    return sigma / std::sqrt(sigma * sigma + omega * omega);
}

Spectrum power_spectrum(const std::vector<double>& x, double dt, double min_peak_hz) {
    Spectrum out;
    if (x.size() < 2) return out;
    double mean = 0;
    for (double v : x) mean += v;
    mean /= double(x.size());
    size_t size = 1;
    while (size < x.size()) size <<= 1;
    std::vector<std::complex<double>> a(size, 0.0);
    double window_power = 0;
    for (size_t k = 0; k < x.size(); ++k) {
        const double w = 0.5 - 0.5 * std::cos(kTwoPi * double(k) / double(x.size()));  // Hann
        a[k] = (x[k] - mean) * w;
        window_power += w * w;
    }
    fft(a);
    const double fs = 1.0 / dt;
    double best = -1;
    for (size_t k = 1; k <= size / 2; ++k) {
        const double f = double(k) * fs / double(size);
        const double psd = (k == size / 2 ? 1.0 : 2.0) * std::norm(a[k]) / (fs * window_power);
        out.frequency_hz.push_back(f);
        out.power.push_back(psd);
        if (f > min_peak_hz && psd > best) best = psd, out.peak_hz = f;
    }
    return out;
}

Result<ModelAnalysis> analyze_model(const TreeModel& tree, const std::string& name,
                                    const AnalysisSettings& s) {
    if (!(s.wind_speed >= 0) || !std::isfinite(s.wind_speed))
        return Status{ErrorCode::invalid_argument, "--wind-speed must be finite and >= 0"};
    if (!(s.step_seconds > 0 && s.step_seconds <= 3600) || !(s.spectrum_seconds > 0 && s.spectrum_seconds <= 3600))
        return Status{ErrorCode::invalid_argument, "--step-seconds and --spectrum-seconds must be in (0, 3600]"};
    HMSM_TRY(validate(s.parameters));
    auto hierarchy = build_hierarchy(tree, s.options, s.parameters);
    if (!hierarchy) return hierarchy.status();
    ModelAnalysis out;
    out.name = name;
    out.nodes = tree.nodes.size();
    out.height = tree_height(tree);
    out.wind_strength = strength_of_speed(s.wind_speed);
    for (size_t i = 1; i < tree.nodes.size(); ++i)
        if (tree.nodes[i].position.y > tree.nodes[size_t(out.top_node)].position.y) out.top_node = int32_t(i);
    const Parameters& p = s.parameters;
    for (size_t c = 0; c < hierarchy->chains.size(); ++c) {
        const Chain& chain = hierarchy->chains[c];
        ChainAnalysis a;
        a.chain = int32_t(c), a.parent = chain.parent, a.depth = chain.depth;
        a.length = chain.length, a.radius = chain.radius;
        a.frequency_hz = std::sqrt(chain.stiffness / chain.inertia) / kTwoPi;
        a.damping_ratio = chain.damping / (2.0 * std::sqrt(chain.stiffness * chain.inertia));
        a.capped = chain.capped;  // the library's flag (docs/model.md 3.4)
        a.static_angle = std::min(p.max_angle, chain.wind_area * out.wind_strength / chain.stiffness);
        a.static_tip_m = chain.length * std::sin(a.static_angle);
        out.chains.push_back(a);
    }
    // Displacements are measured along the horizontal part of the wind direction.
    glm::dvec3 along(s.wind_direction.x, 0.0, s.wind_direction.z);
    along = glm::length(along) > 1e-12 ? glm::normalize(along) : glm::dvec3(1, 0, 0);

    Wind step_wind;
    step_wind.profile = WindProfile::constant;
    step_wind.direction = s.wind_direction;
    step_wind.strength = out.wind_strength;
    step_wind.frequency = 0.0;
    auto step = trace_top(tree, out.top_node, s, step_wind, s.step_seconds, along);
    if (!step) return step.status();
    out.step.deflection = std::move(step).value();
    for (size_t k = 0; k < out.step.deflection.size(); ++k) out.step.time.push_back(double(k + 1) * p.dt);
    fit_oscillation(out.step);

    auto sway = trace_top(tree, out.top_node, s, s.spectrum_wind, s.spectrum_seconds, along);
    if (!sway) return sway.status();
    out.spectrum = power_spectrum(*sway, p.dt, 2.0 / s.spectrum_seconds);
    return out;
}

}  // namespace hmsm::cli
