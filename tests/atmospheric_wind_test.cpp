// The atmospheric wind profile of docs/model.md 3.5 on the host, in double: its constants
// against values computed independently (python3), its spectrum, variances, coherence and
// Taylor advection from time series of the generated wind, and its dependence on the seed.
#include "model/atmospheric_wind.h"
#include "test_trees.h"
#include "analysis.h"

#include <hmsm/hmsm.h>

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <complex>
#include <numbers>
#include <vector>

namespace hmsm {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr uint32_t kV = kAtmosphericModesU, kW = kAtmosphericModesU + kAtmosphericModesV;

/// (u', v', w') at point x and clock (metres travelled), exactly as the devices sum them.
std::array<double, 3> components(const AtmosphericModes& m, const WindFrame& f, const Vec3& x, double clock) {
    return {detail::atmospheric_component(m, 0, kV, clock, 0.0, x, f),
            detail::atmospheric_component(m, kV, kW, clock, 0.0, x, f),
            detail::atmospheric_component(m, kW, kTurbulentModes, clock, 0.0, x, f)};
}

double variance(const std::vector<double>& x) {
    double mean = 0.0, sq = 0.0;
    for (double v : x) mean += v;
    mean /= double(x.size());
    for (double v : x) sq += (v - mean) * (v - mean);
    return sq / double(x.size());
}

double correlation(const std::vector<double>& a, const std::vector<double>& b) {
    double ma = 0.0, mb = 0.0;
    for (size_t i = 0; i < a.size(); ++i) ma += a[i], mb += b[i];
    ma /= double(a.size());
    mb /= double(b.size());
    double ab = 0.0, aa = 0.0, bb = 0.0;
    for (size_t i = 0; i < a.size(); ++i) {
        ab += (a[i] - ma) * (b[i] - mb);
        aa += (a[i] - ma) * (a[i] - ma);
        bb += (b[i] - mb) * (b[i] - mb);
    }
    return ab / std::sqrt(aa * bb);
}

TEST(AtmosphericWind, ModesAndWindMatchIndependentValues) {
    // python3 (the formulas of docs/model.md 3.5): sigma 0.3, seed 7.
    const AtmosphericModes m = atmospheric_modes(0.3, 7);
    EXPECT_NEAR(m.wavenumber[0], 0.0005646465345835727, 1e-17);
    EXPECT_NEAR(m.lateral[0], 0.0016440782022181246, 1e-16);
    EXPECT_NEAR(m.vertical[20], 0.17262420799470288, 1e-14);
    EXPECT_NEAR(m.amplitude[0], 0.09798443613704956, 1e-15);
    EXPECT_NEAR(m.amplitude[17], 0.07581772836785709, 1e-15);
    EXPECT_NEAR(m.amplitude[31], 0.020307753690579803, 1e-15);
    EXPECT_NEAR(m.phase[5], 0.579101204080752, 1e-15);
    EXPECT_NEAR(m.wander_spacing[3], 621.4662564268685, 1e-10);
    EXPECT_NEAR(detail::atmospheric_wander(m, 3, 1234.5), -0.42641119043782305, 1e-14);
    // The wind at (3, 0, -4), t = 2.5 s, strength 1 (U = 6 m/s) along +x: e_y = -z, e_z = +y.
    Wind wind;
    wind.profile = WindProfile::atmospheric;
    wind.turbulence = 0.3;
    wind.seed = 7;
    const Vec3 w = wind_at(wind, {3, 0, -4}, 2.5, 0.0, 1.0);
    EXPECT_NEAR(w.x, 0.906533709250617, 1e-12);
    EXPECT_NEAR(w.z, 0.08127882542711275, 1e-12);
    EXPECT_NEAR(w.y, 0.025214969925126413, 1e-12);
    // The variance of each component is exactly its share: sigma, 0.4 sigma, 0.25 sigma.
    const AtmosphericModes strong = atmospheric_modes(1.5, 3);
    const double expected[3] = {1.5, 0.4 * 1.5, 0.25 * 1.5};
    const uint32_t first[4] = {0, kV, kW, kTurbulentModes};
    for (int c = 0; c < 3; ++c) {
        double v = 0.0;
        for (uint32_t k = first[c]; k < first[c + 1]; ++k) v += strong.amplitude[k] * strong.amplitude[k] / 2.0;
        EXPECT_NEAR(v, expected[c] * expected[c], 1e-12) << c;
    }
}

TEST(AtmosphericWind, FrameAndClock) {
    const WindFrame f = wind_frame({2, 0, 0});
    EXPECT_NEAR(glm::length(f.along - Vec3(1, 0, 0)), 0.0, 1e-15);
    EXPECT_NEAR(glm::length(f.vertical - Vec3(0, 1, 0)), 0.0, 1e-15);  // up for a horizontal wind
    EXPECT_NEAR(glm::dot(f.along, f.lateral), 0.0, 1e-15);
    const WindFrame up = wind_frame({0, 3, 0});  // a vertical wind still has a frame
    EXPECT_NEAR(glm::length(up.lateral), 1.0, 1e-15);
    EXPECT_NEAR(glm::dot(up.along, up.lateral), 0.0, 1e-15);
    Wind wind;
    wind.profile = WindProfile::atmospheric;
    wind.strength = 4.0;
    EXPECT_DOUBLE_EQ(wind_clock_rate(wind), 12.0);  // the mean wind speed
    wind.profile = WindProfile::turbulent;
    EXPECT_DOUBLE_EQ(wind_clock_rate(wind), wind.frequency);
}

TEST(AtmosphericWind, SpectrumHasTheKaimalSlopeAndTheRequestedVariances) {
    // u'(t) at one point of a 6 m/s wind, 2^16 samples 0.05 s apart (55 minutes), eight seeds:
    // the Hann-windowed periodogram summed over quarter-decade bands from 0.15 to 4 Hz (the
    // inertial range: kappa L_u from 1.4 to 38) falls as f^(-5/3) (Kaimal's local slope there
    // is -1.5 ... -1.65); the variances are sigma^2 and the intensity ratios those of IEC 61400-1.
    const double sigma = 0.4, speed = 6.0, dt = 0.05;
    const size_t n = size_t(1) << 16;
    const WindFrame frame = wind_frame({1, 0, 0});
    std::vector<double> band_power(6, 0.0);
    const double band_low = 0.15, band_step = std::pow(10.0, 0.25);
    for (uint64_t seed = 1; seed <= 8; ++seed) {
        const AtmosphericModes m = atmospheric_modes(sigma, seed);
        std::vector<double> u(n), v(n), w(n);
        for (size_t i = 0; i < n; ++i) {
            const auto c = components(m, frame, Vec3(0.0), speed * dt * double(i));
            u[i] = c[0];
            v[i] = c[1];
            w[i] = c[2];
        }
        const double su = std::sqrt(variance(u));
        EXPECT_NEAR(su, sigma, 0.03 * sigma) << seed;
        EXPECT_NEAR(std::sqrt(variance(v)) / su, 0.8 / 2.0, 0.02) << seed;   // sigma_v / sigma_u = 0.8
        EXPECT_NEAR(std::sqrt(variance(w)) / su, 0.5 / 2.0, 0.0125) << seed;   // sigma_w / sigma_u = 0.5
        std::vector<std::complex<double>> spectrum(n);
        for (size_t i = 0; i < n; ++i)
            spectrum[i] = u[i] * 0.5 * (1.0 - std::cos(2.0 * kPi * double(i) / double(n)));
        cli::fft(spectrum);
        for (size_t j = 1; j < n / 2; ++j) {
            const double f = double(j) / (double(n) * dt);
            const double band = std::floor(std::log(f / band_low) / std::log(band_step));
            if (band >= 0.0 && band < double(band_power.size())) band_power[size_t(band)] += std::norm(spectrum[j]);
        }
    }
    // Least-squares slope of log(power per Hz) against log(f) over the band centres.
    double sx = 0.0, sy = 0.0, sxx = 0.0, sxy = 0.0;
    const double count = double(band_power.size());
    for (size_t b = 0; b < band_power.size(); ++b) {
        ASSERT_GT(band_power[b], 0.0) << b;
        const double low = band_low * std::pow(band_step, double(b)), high = low * band_step;
        const double x = std::log(std::sqrt(low * high)), y = std::log(band_power[b] / (high - low));
        sx += x, sy += y, sxx += x * x, sxy += x * y;
    }
    const double slope = (count * sxy - sx * sy) / (count * sxx - sx * sx);
    EXPECT_NEAR(slope, -5.0 / 3.0, 0.25);
}

TEST(AtmosphericWind, OneSeedsSpectrumIsContinuous) {
    // u'(t) of one seed at one point of a 6 m/s wind (2^16 samples 0.05 s apart): averaged over
    // bands of 1/20 decade from 0.15 to 4 Hz, the periodogram stays within a factor of 10 of a
    // power law fitted to it. Lines of fixed frequency (16 over four decades) would leave bands
    // between them 10^-4 ... 10^-6 below it.
    const double speed = 6.0, dt = 0.05;
    const size_t n = size_t(1) << 16;
    const AtmosphericModes m = atmospheric_modes(0.4, 1);
    const WindFrame frame = wind_frame({1, 0, 0});
    std::vector<std::complex<double>> spectrum(n);
    for (size_t i = 0; i < n; ++i)
        spectrum[i] = components(m, frame, Vec3(0.0), speed * dt * double(i))[0] * 0.5 *
                      (1.0 - std::cos(2.0 * kPi * double(i) / double(n)));
    cli::fft(spectrum);
    const double band_low = 0.15, band_step = std::pow(10.0, 0.05);
    const size_t bands = size_t(std::floor(std::log(4.0 / band_low) / std::log(band_step)));
    std::vector<double> power(bands, 0.0), count(bands, 0.0);
    for (size_t j = 1; j < n / 2; ++j) {
        const double f = double(j) / (double(n) * dt);
        const double band = std::floor(std::log(f / band_low) / std::log(band_step));
        if (band >= 0.0 && band < double(bands)) power[size_t(band)] += std::norm(spectrum[j]), count[size_t(band)] += 1.0;
    }
    std::vector<double> xs, ys;
    for (size_t b = 0; b < bands; ++b) {
        ASSERT_GT(count[b], 0.0) << b;
        xs.push_back(std::log(band_low * std::pow(band_step, double(b) + 0.5)));
        ys.push_back(std::log(power[b] / count[b]));
    }
    double sx = 0.0, sy = 0.0, sxx = 0.0, sxy = 0.0;
    for (size_t b = 0; b < bands; ++b) sx += xs[b], sy += ys[b], sxx += xs[b] * xs[b], sxy += xs[b] * ys[b];
    const double slope = (double(bands) * sxy - sx * sy) / (double(bands) * sxx - sx * sx);
    const double intercept = (sy - slope * sx) / double(bands);
    double lowest = 0.0, highest = 0.0;
    for (size_t b = 0; b < bands; ++b) {
        lowest = std::min(lowest, ys[b] - (intercept + slope * xs[b]));
        highest = std::max(highest, ys[b] - (intercept + slope * xs[b]));
    }
    EXPECT_GT(lowest, std::log(0.1)) << "slope " << slope;
    EXPECT_LT(highest, std::log(10.0)) << "slope " << slope;
    EXPECT_NEAR(slope, -5.0 / 3.0, 0.4);
}

TEST(AtmosphericWind, CoherenceFallsWithCrossWindDistanceAsDavenports) {
    // Correlation of u' between two points r apart across a 6 m/s wind, averaged over 16
    // seeds, against the mean of the modes' expected coherence sum a_k^2 exp(-12 kx_k r) / sum a_k^2.
    const double speed = 6.0, dt = 0.25;
    const size_t n = 8192;
    const WindFrame frame = wind_frame({1, 0, 0});
    const double distances[] = {2.0, 10.0, 40.0};
    double measured[3] = {}, expected[3] = {};
    const int seeds = 16;
    for (uint64_t seed = 100; seed < 100 + seeds; ++seed) {
        const AtmosphericModes m = atmospheric_modes(0.3, seed);
        std::vector<double> here(n);
        for (size_t i = 0; i < n; ++i) here[i] = components(m, frame, Vec3(0.0), speed * dt * double(i))[0];
        for (int d = 0; d < 3; ++d) {
            std::vector<double> there(n);
            for (size_t i = 0; i < n; ++i)
                there[i] = components(m, frame, distances[d] * frame.lateral, speed * dt * double(i))[0];
            measured[d] += correlation(here, there) / seeds;
            double weighted = 0.0, total = 0.0;
            for (uint32_t k = 0; k < kV; ++k) {
                const double a2 = m.amplitude[k] * m.amplitude[k];
                weighted += a2 * std::exp(-12.0 * m.wavenumber[k] * distances[d]);
                total += a2;
            }
            expected[d] += weighted / total / seeds;
        }
    }
    for (int d = 0; d < 3; ++d) EXPECT_NEAR(measured[d], expected[d], 0.15) << distances[d];
    EXPECT_GT(measured[0], measured[1]);
    EXPECT_GT(measured[1], measured[2]);
    EXPECT_GT(measured[0], 0.55);  // neighbours sway largely together
    EXPECT_LT(measured[2], 0.35);  // a stand 40 m away feels other gusts
}

TEST(AtmosphericWind, GustsTravelWithTheMeanWind) {
    // Taylor's frozen turbulence, up to the wander: the wind at x + D d follows the wind at x
    // D/U later, and decorrelates slowly with D.
    Wind wind;
    wind.profile = WindProfile::atmospheric;
    wind.direction = {3, 0, 4};
    wind.strength = 2.25;  // U = 9 m/s
    wind.turbulence = 0.8;
    wind.seed = 12;
    const Vec3 d = glm::normalize(wind.direction), x(5, 1, -7);
    auto along = [&](const Vec3& at, double t0) {
        std::vector<double> series;
        for (int i = 0; i < 6000; ++i) series.push_back(glm::dot(wind_at(wind, at, t0 + 0.1 * i), d));
        return series;
    };
    const std::vector<double> here = along(x, 0.0);
    double last = 1.0;
    for (double distance : {4.0, 30.0, 200.0}) {
        const double delayed = correlation(here, along(x + distance * d, distance / 9.0));
        const double at_once = correlation(here, along(x + distance * d, 0.0));
        EXPECT_GT(delayed, at_once + 0.1) << distance;
        EXPECT_LT(delayed, last) << distance;
        last = delayed;
    }
    EXPECT_GT(correlation(here, along(x + 4.0 * d, 4.0 / 9.0)), 0.9);  // 0.945
    // Against d with a negative strength.
    wind.strength = -2.25;
    const std::vector<double> back = along(x, 0.0);
    EXPECT_GT(correlation(back, along(x - 12.0 * d, 12.0 / 9.0)), 0.8);  // 0.881
    double mean_along = 0.0;  // the mean wind blows against d
    for (double v : back) mean_along += v / double(back.size());
    EXPECT_NEAR(mean_along, -2.25, 0.5);
}

TEST(AtmosphericWind, TheSeedDeterminesTheWind) {
    Wind wind;
    wind.profile = WindProfile::atmospheric;
    wind.turbulence = 0.5;
    wind.seed = 42;
    Wind same = wind, other = wind;
    other.seed = 43;
    double largest = 0.0;
    for (double t = 0.0; t < 60.0; t += 0.7) {
        EXPECT_EQ(wind_at(wind, {1, 0, 2}, t), wind_at(same, {1, 0, 2}, t));
        largest = std::max(largest, glm::length(wind_at(wind, {1, 0, 2}, t) - wind_at(other, {1, 0, 2}, t)));
    }
    EXPECT_GT(largest, 0.2);
    // The along-wind component is what wind_value reports.
    EXPECT_NEAR(wind_value(wind, 6.0 * 2.0), wind_at(wind, {0, 0, 0}, 2.0).x, 1e-12);
}

/// Angles of every chain of instance `instance` after `steps` steps of `config` on cpu64.
std::vector<double> instance_angles(const Scene& scene, const SimulationConfig& config, uint32_t steps,
                                    size_t instance) {
    auto sim = Simulation::create(scene, config);
    EXPECT_TRUE(sim.ok()) << sim.status().message();
    if (!sim.ok()) return {};
    EXPECT_TRUE((*sim)->step(steps).ok());
    std::vector<double> angles;
    EXPECT_TRUE((*sim)->read(Output::chain_angles, angles).ok());
    const size_t per = angles.size() / scene.instances.size();
    return {angles.begin() + std::ptrdiff_t(instance * per), angles.begin() + std::ptrdiff_t((instance + 1) * per)};
}

double largest_difference(const std::vector<double>& a, const std::vector<double>& b) {
    double d = 0.0;
    for (size_t i = 0; i < a.size() && i < b.size(); ++i) d = std::max(d, std::abs(a[i] - b[i]));
    return d;
}

TEST(AtmosphericWind, TreesFarApartAcrossTheWindSwayDifferently) {
    // Two identical trees 60 m apart across the wind: under `turbulent` (no front) they sway
    // alike; under `atmospheric` each feels its own gusts. The seed decides the motion.
    Scene scene;
    scene.models = {test::small_tree()};
    scene.model_names = {"small"};
    scene.instances = {{0, {0, 0, 0}, 0.0}, {0, {0, 0, 60}, 0.0}};
    SimulationConfig config;
    config.backend = BackendKind::cpu64;
    config.wind.profile = WindProfile::turbulent;
    config.wind.strength = 4.0;
    config.wind.turbulence = 0.8;
    config.parameters.wind_gain = 4.0;
    const uint32_t steps = 360;
    const auto near = instance_angles(scene, config, steps, 0), far = instance_angles(scene, config, steps, 1);
    EXPECT_EQ(largest_difference(near, far), 0.0);
    config.wind.profile = WindProfile::atmospheric;
    const auto near_a = instance_angles(scene, config, steps, 0), far_a = instance_angles(scene, config, steps, 1);
    EXPECT_GT(largest_difference(near_a, far_a), 1e-3);
    EXPECT_EQ(largest_difference(near_a, instance_angles(scene, config, steps, 0)), 0.0);
    config.wind.seed = 1;
    EXPECT_GT(largest_difference(near_a, instance_angles(scene, config, steps, 0)), 1e-3);
}

}  // namespace
}  // namespace hmsm
