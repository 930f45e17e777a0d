// See tree_response.h.
#include "tree_response.h"

#include "model/linearized_links.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>

namespace hmsm::cli {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

struct Probe {
    int32_t top = 0, base = 0;
    glm::dvec3 along{1, 0, 0}, cross{0, 0, 1};
};

/// Positions of the top and base nodes after every step.
struct Track {
    std::vector<glm::dvec3> top, base;
};

Result<std::unique_ptr<Simulation>> create(const TreeModel& tree, const TreeResponseSettings& s, const Wind& wind) {
    TreeModel model = tree;
    // Under paper leaves do not act on the motion; under coupled they carry mass and drag.
    if (s.options.dynamics == Dynamics::paper) model.leaves.clear();
    SimulationConfig config;
    config.backend = BackendKind::cpu64;
    config.model = s.options;
    config.model.ring_sides = 3;
    config.parameters = s.parameters;
    config.wind = wind;
    config.outputs = Outputs::joints_and_nodes;
    return Simulation::create(single_tree_scene(std::move(model)), config);
}

Status advance(Simulation& sim, const TreeResponseSettings& s, double seconds, const Probe& probe, Track* track) {
    const uint64_t steps = uint64_t(std::ceil(seconds / s.parameters.dt));
    if (steps > 20'000'000) return Status{ErrorCode::invalid_argument, "analysis run too long: more than 2e7 steps"};
    std::vector<double> xyz;
    for (uint64_t k = 0; k < steps; ++k) {
        HMSM_TRY(sim.step(1));
        if (s.on_step) s.on_step();
        if (!track) continue;
        HMSM_TRY(sim.read(Output::node_positions, xyz));
        auto at = [&](int32_t n) { return glm::dvec3(xyz[3 * size_t(n)], xyz[3 * size_t(n) + 1], xyz[3 * size_t(n) + 2]); };
        track->top.push_back(at(probe.top));
        track->base.push_back(at(probe.base));
    }
    return {};
}

double rms_about_mean(const std::vector<double>& x, double& mean) {
    mean = 0;
    for (double v : x) mean += v;
    mean /= double(std::max<size_t>(1, x.size()));
    double sum = 0;
    for (double v : x) sum += (v - mean) * (v - mean);
    return std::sqrt(sum / double(std::max<size_t>(1, x.size())));
}

double largest_magnitude(const std::vector<double>& x) {
    double largest = 0;
    for (double v : x) largest = std::max(largest, std::abs(v));
    return largest;
}

/// A free decay's upward zero crossings and the peak of each cycle between two of them.
struct DecayCycles {
    std::vector<double> crossing, peak_t, peak;
    /// Crossings the fits use: those that close a cycle with a peak.
    size_t used() const { return std::min(crossing.size(), peak.size() + 1); }
    /// Cycles per second between the first and the last used crossing; 0 with fewer than 3 crossings.
    double frequency_hz() const {
        return crossing.size() < 3 ? 0.0 : double(used() - 1) / (crossing[used() - 1] - crossing[0]);
    }
};

/// Upward zero crossings with hysteresis (a crossing counts once the signal has been below
/// -h since the last one), interpolated linearly; the cycle's peak is the largest value between
/// two crossings. Stops once the peaks sink below 2 % of the first: the rest is the ripple of
/// faster modes. `largest` is the largest |x| (> 0).
DecayCycles decay_cycles(const std::vector<double>& time, const std::vector<double>& x, double largest) {
    const double h = 0.02 * largest;
    DecayCycles c;
    bool armed = false;
    double best = 0, best_t = 0;
    for (size_t i = 1; i < x.size(); ++i) {
        if (x[i] < -h) armed = true;
        if (armed && x[i - 1] < 0 && x[i] >= 0) {
            const double t = time[i - 1] + (time[i] - time[i - 1]) * (-x[i - 1]) / (x[i] - x[i - 1]);
            if (!c.crossing.empty() && best > 0) {
                if (!c.peak.empty() && best < 0.02 * c.peak.front()) break;
                c.peak_t.push_back(best_t), c.peak.push_back(best);
            }
            c.crossing.push_back(t);
            armed = false, best = 0;
        }
        if (!c.crossing.empty() && x[i] > best) best = x[i], best_t = time[i];
    }
    return c;
}

}  // namespace

void fit_release(ReleaseTest& r, double dt) {
    r.frequency_hz = r.fft_frequency_hz = r.damping_ratio = 0;
    r.cycles = 0;
    const std::vector<double>& x = r.displacement;
    if (x.size() < 8) return;
    const double largest = largest_magnitude(x);
    if (!(largest > 0)) return;
    const DecayCycles cycles = decay_cycles(r.time, x, largest);
    if (cycles.crossing.size() >= 3) {
        r.cycles = int(cycles.used() - 1);
        r.frequency_hz = cycles.frequency_hz();
        r.damping_ratio = decay_damping_ratio(cycles.peak_t, cycles.peak, r.frequency_hz);
    }
    // The decay's spectrum, zero-padded four times, peak refined by a parabola through log power.
    std::vector<double> padded = x;
    padded.resize(4 * x.size(), 0.0);
    const Spectrum spectrum = power_spectrum(padded, dt, 0.0);
    size_t k = 0;
    for (size_t i = 0; i < spectrum.power.size(); ++i)
        if (spectrum.power[i] > spectrum.power[k]) k = i;
    double offset = 0;
    if (k > 0 && k + 1 < spectrum.power.size() && spectrum.power[k - 1] > 0 && spectrum.power[k + 1] > 0) {
        const double a = std::log(spectrum.power[k - 1]), b = std::log(spectrum.power[k]), c = std::log(spectrum.power[k + 1]);
        if (a - 2 * b + c < 0) offset = 0.5 * (a - c) / (a - 2 * b + c);
    }
    const double df = spectrum.frequency_hz.size() > 1 ? spectrum.frequency_hz[1] - spectrum.frequency_hz[0] : 0.0;
    if (!spectrum.frequency_hz.empty()) r.fft_frequency_hz = spectrum.frequency_hz[k] + offset * df;
}

double decay_frequency(const std::vector<double>& displacement, double dt) {
    if (displacement.size() < 8) return 0.0;
    const double largest = largest_magnitude(displacement);
    if (!(largest > 0)) return 0.0;
    std::vector<double> time(displacement.size());
    for (size_t i = 0; i < time.size(); ++i) time[i] = double(i) * dt;
    return decay_cycles(time, displacement, largest).frequency_hz();
}

double log_log_slope(const Spectrum& s, double low, double high, int& bins) {
    bins = 0;
    if (!(low > 0) || !(high > low)) return 0.0;
    const double width = 0.05;  // decades
    const int count = int(std::ceil(std::log10(high / low) / width));
    std::vector<double> sum(size_t(std::max(count, 0)), 0.0), logf(sum.size(), 0.0);
    std::vector<int> n(sum.size(), 0);
    for (size_t k = 0; k < s.frequency_hz.size(); ++k) {
        const double f = s.frequency_hz[k];
        if (f < low || f > high || !(s.power[k] > 0)) continue;
        const int b = std::min(count - 1, int(std::log10(f / low) / width));
        sum[size_t(b)] += s.power[k], logf[size_t(b)] += std::log10(f), ++n[size_t(b)];
    }
    std::vector<double> lx, ly;
    for (size_t b = 0; b < sum.size(); ++b)
        if (n[b] > 0) lx.push_back(logf[b] / n[b]), ly.push_back(std::log10(sum[b] / n[b]));
    bins = int(lx.size());
    if (lx.size() < 3) return 0.0;
    double mx = 0, my = 0;
    for (size_t i = 0; i < lx.size(); ++i) mx += lx[i], my += ly[i];
    mx /= double(lx.size()), my /= double(lx.size());
    double sxx = 0, sxy = 0;
    for (size_t i = 0; i < lx.size(); ++i) sxx += (lx[i] - mx) * (lx[i] - mx), sxy += (lx[i] - mx) * (ly[i] - my);
    return sxx > 0 ? sxy / sxx : 0.0;
}

Result<TreeResponse> analyze_tree_response(const TreeModel& tree, const std::string& name,
                                           const TreeResponseSettings& s) {
    auto in_range = [](double v, double lo, double hi) { return std::isfinite(v) && v >= lo && v <= hi; };
    if (!in_range(s.pull_speed, 0.1, 100.0))
        return Status{ErrorCode::invalid_argument, "--pull-speed must be in [0.1, 100] m/s"};
    for (double v : s.sway_speeds)
        if (!in_range(v, 0.1, 100.0))
            return Status{ErrorCode::invalid_argument, "--sway-speeds: " + std::to_string(v) + " is not in [0.1, 100] m/s"};
    if (s.sway_speeds.size() > 16) return Status{ErrorCode::invalid_argument, "--sway-speeds: at most 16 speeds"};
    for (double v : {s.pull_seconds, s.release_seconds, s.sway_seconds, s.settle_seconds})
        if (!in_range(v, 0.0, 3600.0))
            return Status{ErrorCode::invalid_argument, "--pull-seconds, --release-seconds, --sway-seconds and "
                                                       "--settle-seconds must be in [0, 3600]"};
    if (!(s.release_seconds > 0)) return Status{ErrorCode::invalid_argument, "--release-seconds must be > 0"};
    HMSM_TRY(validate(s.parameters));
    HMSM_TRY(validate_tree(tree));
    TreeResponse out;
    out.name = name;
    out.nodes = tree.nodes.size();
    out.height = tree_height(tree);
    for (size_t i = 1; i < tree.nodes.size(); ++i)
        if (tree.nodes[i].position.y > tree.nodes[size_t(out.top_node)].position.y) out.top_node = int32_t(i);
    out.base_node = out.top_node;
    while (out.base_node > 0 && tree.nodes[size_t(out.base_node)].parent > 0)
        out.base_node = tree.nodes[size_t(out.base_node)].parent;
    {
        // Radius linear along each segment of the path from the root to the top node.
        const double breast = tree.nodes[0].position.y + 1.3;
        out.dbh = 2.0 * tree.nodes[0].radius;
        for (int32_t n = out.top_node; n > 0; n = tree.nodes[size_t(n)].parent) {
            const TreeNode& a = tree.nodes[size_t(tree.nodes[size_t(n)].parent)];
            const TreeNode& b = tree.nodes[size_t(n)];
            if ((a.position.y - breast) * (b.position.y - breast) <= 0 && a.position.y != b.position.y) {
                const double u = (breast - a.position.y) / (b.position.y - a.position.y);
                out.dbh = 2.0 * (a.radius + u * (b.radius - a.radius));
            }
        }
    }
    Probe probe{out.top_node, out.base_node};
    glm::dvec3 along(s.wind_direction.x, 0.0, s.wind_direction.z);
    probe.along = glm::length(along) > 1e-12 ? glm::normalize(along) : glm::dvec3(1, 0, 0);
    probe.cross = glm::cross(glm::dvec3(0, 1, 0), probe.along);
    const glm::dvec3 top_rest = tree.nodes[size_t(out.top_node)].position;
    const glm::dvec3 root = tree.nodes[0].position;
    const glm::dvec3 base_rest = glm::normalize(tree.nodes[size_t(out.base_node)].position - root);
    const double dt = s.parameters.dt;

    // Release test: a constant wind bends the tree, then stops; the top decays freely.
    Wind pull;
    pull.profile = WindProfile::constant;
    pull.direction = s.wind_direction;
    pull.strength = wind_strength_for_speed(s.pull_speed);
    pull.frequency = 0.0;
    {
        auto sim = create(tree, s, pull);
        if (!sim) return sim.status();
        HMSM_TRY(advance(**sim, s, s.pull_seconds, probe, nullptr));
        Wind calm = pull;
        calm.profile = WindProfile::none;
        HMSM_TRY((*sim)->set_wind(calm));
        std::vector<double> xyz;
        HMSM_TRY((*sim)->read(Output::node_positions, xyz));
        const glm::dvec3 at_release(xyz[3 * size_t(out.top_node)], xyz[3 * size_t(out.top_node) + 1],
                                    xyz[3 * size_t(out.top_node) + 2]);
        out.release.pulled_m = glm::dot(at_release - top_rest, probe.along);
        Track track;
        HMSM_TRY(advance(**sim, s, s.release_seconds, probe, &track));
        for (size_t k = 0; k < track.top.size(); ++k) {
            out.release.time.push_back(double(k + 1) * dt);
            out.release.displacement.push_back(glm::dot(track.top[k] - top_rest, probe.along));
        }
        fit_release(out.release, dt);
    }
    if (s.options.dynamics == Dynamics::coupled) {
        auto links = analyze_link_modes(tree, s, 6);
        if (!links) return links.status();
        out.links = std::move(links).value();
    }
    const double f0 = out.release.frequency_hz > 0 ? out.release.frequency_hz : out.release.fft_frequency_hz;

    for (double speed : s.sway_speeds) {
        Wind wind;
        wind.profile = WindProfile::atmospheric;
        wind.direction = s.wind_direction;
        wind.strength = wind_strength_for_speed(speed);
        wind.turbulence = s.turbulence;
        wind.seed = s.seed;
        auto sim = create(tree, s, wind);
        if (!sim) return sim.status();
        HMSM_TRY(advance(**sim, s, s.settle_seconds, probe, nullptr));
        Track track;
        HMSM_TRY(advance(**sim, s, s.sway_seconds, probe, &track));
        SwayRun run;
        run.speed = speed, run.strength = wind.strength;
        std::vector<double> a, c;
        double lean = 0;
        for (size_t k = 0; k < track.top.size(); ++k) {
            a.push_back(glm::dot(track.top[k] - top_rest, probe.along));
            c.push_back(glm::dot(track.top[k] - top_rest, probe.cross));
            const glm::dvec3 d = glm::normalize(track.base[k] - root);
            lean += std::acos(std::clamp(glm::dot(d, base_rest), -1.0, 1.0));
        }
        double mean_cross = 0;
        run.rms_along_m = rms_about_mean(a, run.mean_along_m);
        run.rms_cross_m = rms_about_mean(c, mean_cross);
        run.cross_ratio = run.rms_along_m > 0 ? run.rms_cross_m / run.rms_along_m : 0.0;
        run.mean_lean_rad = track.top.empty() ? 0.0 : lean / double(track.top.size());
        run.mean_top_over_height = out.height > 0 ? std::hypot(run.mean_along_m, mean_cross) / out.height : 0.0;
        run.along = power_spectrum(a, dt, 2.0 / std::max(s.sway_seconds, dt));
        run.band_low_hz = 1.5 * f0;
        run.band_high_hz = std::min(10.0 * f0, 0.25 / dt);
        run.slope = log_log_slope(run.along, run.band_low_hz, run.band_high_hz, run.band_bins);
        out.sway.push_back(std::move(run));
    }
    return out;
}

Result<LinkModesReport> analyze_link_modes(const TreeModel& tree, const TreeResponseSettings& s, int modes) {
    const Parameters parameters = parameters_for_tree(tree, s.parameters);
    auto h = build_hierarchy(tree, s.options, parameters);
    if (!h) return h.status();
    glm::dvec3 along(s.wind_direction.x, 0.0, s.wind_direction.z);
    along = glm::length(along) > 1e-12 ? glm::normalize(along) : glm::dvec3(1, 0, 0);
    const detail::LinearizedLinks links = detail::linearize_links(tree, *h, parameters);
    const detail::LinkModes found =
        detail::lowest_link_modes(links, modes, {along, glm::cross(glm::dvec3(0, 1, 0), along)});
    LinkModesReport report;
    report.frequency_hz = found.frequency_hz;
    report.mass_share = found.mass_share;
    report.sway_hz = found.sway_hz;
    report.converged = found.converged;
    for (int a = 0; a < 2; ++a) report.trunk_f0_hz[size_t(a)] = h->chains[0].dynamics.frequency[a];
    return report;
}

}  // namespace hmsm::cli
