// hmsm analyze --whole-tree (tools/hmsm/tree_response.cpp): the release test's fits on a known
// decay, the spectrum slope on a known power law, a uniform rod's f0 and damping against the
// cantilever and the damping set under both dynamics, and the command line.
#include "cli_fixture.h"
#include "model/coupled_constants.h"
#include "test_trees.h"
#include "tree_response.h"

#include <nlohmann/json.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

using namespace hmsm;

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

TEST(TreeResponse, ReleaseFitRecoversADecay) {
    cli::ReleaseTest r;
    const double f = 0.4, zeta = 0.04, dt = 1.0 / 120.0;
    const double omega = kTwoPi * f / std::sqrt(1 - zeta * zeta);
    for (int k = 1; k <= 120 * 60; ++k) {
        const double t = k * dt;
        r.time.push_back(t);
        r.displacement.push_back(0.5 * std::exp(-zeta * omega * t) * std::cos(kTwoPi * f * t));
    }
    cli::fit_release(r, dt);
    EXPECT_NEAR(r.frequency_hz, f, 0.002 * f);
    EXPECT_NEAR(r.fft_frequency_hz, f, 0.02 * f);
    EXPECT_NEAR(r.damping_ratio, zeta, 0.002);
    EXPECT_GE(r.cycles, 10);
    // The same crossings from the samples alone (times counted from the first sample).
    EXPECT_NEAR(cli::decay_frequency(r.displacement, dt), r.frequency_hz, 1e-9 * f);
    EXPECT_EQ(cli::decay_frequency({0.1, -0.1, 0.1}, dt), 0.0);
}

TEST(TreeResponse, SlopeOfAPowerLaw) {
    cli::Spectrum s;
    for (int k = 1; k <= 4000; ++k) {
        s.frequency_hz.push_back(k * 0.01);
        s.power.push_back(7.0 * std::pow(k * 0.01, -3.0));
    }
    int bins = 0;
    EXPECT_NEAR(cli::log_log_slope(s, 0.5, 5.0, bins), -3.0, 1e-3);
    EXPECT_EQ(bins, 20);
    EXPECT_EQ(cli::log_log_slope(s, 5.0, 0.5, bins), 0.0);
    EXPECT_EQ(bins, 0);
}

cli::TreeResponseSettings quick(Dynamics dynamics) {
    cli::TreeResponseSettings s;
    s.options.dynamics = dynamics;
    s.pull_seconds = 10.0;
    s.release_seconds = 40.0;
    s.sway_speeds = {10.0};
    s.settle_seconds = 5.0;
    s.sway_seconds = 40.0;
    return s;
}

// A uniform rod under coupled is one cantilever: its release sways at 1.8751^2/(2 pi) sqrt(EJ/(mu L^4))
// (Rayleigh's estimate is 0.4 % above) and decays with exactly the structural damping (no wind, no
// aerodynamic damping).
TEST(TreeResponse, CoupledRodMatchesTheCantileverAndTheDampingSet) {
    const double L = 20.0, r = 0.2;
    for (double zeta : {0.03, 0.08}) {
        cli::TreeResponseSettings s = quick(Dynamics::coupled);
        s.parameters.structural_damping = zeta;
        auto a = cli::analyze_tree_response(test::rod(4, L, r), "rod", s);
        ASSERT_TRUE(a.ok()) << a.status().message();
        const double f0 = detail::uniform_cantilever_frequency(L, r, s.parameters.material);
        const double damped = f0 * std::sqrt(1 - zeta * zeta);
        EXPECT_NEAR(a->release.frequency_hz, damped, 0.02 * damped);
        EXPECT_NEAR(a->release.fft_frequency_hz, damped, 0.03 * damped);
        EXPECT_NEAR(a->release.damping_ratio, zeta, 0.1 * zeta);
        EXPECT_GT(a->release.pulled_m, 0.0);
        EXPECT_NEAR(a->dbh, 2.0 * r, 1e-12);
        EXPECT_NEAR(a->height, L, 1e-12);
        EXPECT_GE(a->release.cycles, 5);
        ASSERT_EQ(a->sway.size(), 1u);
        const cli::SwayRun& w = a->sway[0];
        EXPECT_GT(w.mean_along_m, 0.0);  // pushed downwind
        EXPECT_GT(w.mean_top_over_height, 0.0);
        EXPECT_GT(w.mean_lean_rad, 0.0);
        // The rod is split into links that bend (docs/model.md 3.13): its base leans less than a
        // rigid hinge would, angle < displacement / height.
        EXPECT_LT(w.mean_lean_rad, 0.8 * w.mean_top_over_height);
        EXPECT_GT(w.cross_ratio, 0.0);
        EXPECT_LT(w.cross_ratio, 2.0);
        EXPECT_NEAR(w.band_low_hz, 1.5 * a->release.frequency_hz, 1e-12);
        EXPECT_GE(w.band_bins, 3);
        EXPECT_LT(w.slope, 0.0);
    }
}

// Under paper the rod's release follows its chain constants: sqrt(K/I) and the damping ratio zeta.
TEST(TreeResponse, PaperRodMatchesItsChainConstants) {
    cli::TreeResponseSettings s = quick(Dynamics::paper);
    s.sway_speeds.clear();
    auto a = cli::analyze_tree_response(test::rod(4, 20.0, 0.2), "rod", s);
    ASSERT_TRUE(a.ok()) << a.status().message();
    const double K = 1e7 * std::pow(0.2, 4) / 20.0, I = 0.2 * 0.2 * 8000.0;
    const double damped = std::sqrt(K / I) / kTwoPi * std::sqrt(1 - 0.01);
    EXPECT_NEAR(a->release.frequency_hz, damped, 0.02 * damped);
    EXPECT_NEAR(a->release.damping_ratio, 0.1, 0.01);
    EXPECT_TRUE(a->sway.empty());
}

TEST(TreeResponse, RefusesBadSettings) {
    cli::TreeResponseSettings s = quick(Dynamics::coupled);
    s.sway_speeds = {10.0, -5.0};
    auto a = cli::analyze_tree_response(test::rod(), "rod", s);
    ASSERT_FALSE(a.ok());
    EXPECT_NE(a.status().message().find("-5"), std::string::npos) << a.status().message();
    s = quick(Dynamics::coupled);
    s.release_seconds = 0.0;
    EXPECT_FALSE(cli::analyze_tree_response(test::rod(), "rod", s).ok());
    s = quick(Dynamics::coupled);
    s.pull_speed = std::nan("");
    EXPECT_FALSE(cli::analyze_tree_response(test::rod(), "rod", s).ok());
}

class WholeTreeCli : public test::CliFixture {};

TEST_F(WholeTreeCli, WritesTheReportAndPlots) {
    const std::string quick_run = " --whole-tree --pull-seconds 3 --release-seconds 12 --settle-seconds 1"
                                  " --sway-seconds 8 --sway-speeds 5,20 --no-progress";
    ASSERT_EQ(run("analyze --preset paper-5 --dynamics coupled --json" + quick_run + " --plot-release " +
                  path("release.png") + " --plot-sway " + path("sway.png")).exit_code,
              0)
        << last_.err;
    auto j = nlohmann::json::parse(last_.out);
    ASSERT_EQ(j["models"].size(), 1u);
    const auto& m = j["models"][0];
    EXPECT_EQ(m["dynamics"], "coupled");
    EXPECT_GT(m["release"]["frequency_hz"].get<double>(), 0.0);
    EXPECT_GT(m["release"]["damping_ratio"].get<double>(), 0.0);
    ASSERT_EQ(m["sway"].size(), 2u);
    EXPECT_EQ(m["sway"][1]["speed_m_s"].get<double>(), 20.0);
    // A stronger wind leans the tree further.
    EXPECT_GT(m["sway"][1]["mean_lean_deg"].get<double>(), m["sway"][0]["mean_lean_deg"].get<double>());
    // The linearized links: six modes, lowest first, and a sway below the trunk chain's own f0
    // (the limbs bend); the paper dynamics reports none.
    const auto& links = m["linearized_links"];
    ASSERT_EQ(links["modes_hz"].size(), 6u);
    EXPECT_TRUE(links["converged"].get<bool>());
    for (size_t k = 1; k < 6; ++k)
        EXPECT_GE(links["modes_hz"][k].get<double>(), links["modes_hz"][k - 1].get<double>());
    EXPECT_GT(links["sway_along_hz"].get<double>(), 0.0);
    EXPECT_LT(links["sway_along_hz"].get<double>(), links["trunk_f0_hz"][0].get<double>());
    for (const char* png : {"release.png", "sway.png"}) {
        const std::string bytes = test::read_text(path(png));
        ASSERT_GT(bytes.size(), 1000u) << png;
        EXPECT_EQ(bytes.substr(1, 3), "PNG") << png;
    }
    ASSERT_EQ(run("analyze --preset paper-5" + quick_run).exit_code, 0) << last_.err;
    EXPECT_NE(last_.out.find("release test"), std::string::npos);
    EXPECT_NE(last_.out.find("paper dynamics"), std::string::npos);
    EXPECT_EQ(last_.out.find("linearized links"), std::string::npos);
}

TEST_F(WholeTreeCli, RefusesBadInputWithoutPlots) {
    const std::string plots = " --whole-tree --plot-release " + path("r.png") + " --plot-sway " + path("s.png");
    expect_bad_input("analyze --preset paper-1 --sway-speeds 10,-3" + plots, "-3");
    expect_bad_input("analyze --preset paper-1 --release-seconds 0" + plots, "--release-seconds");
    expect_bad_input("analyze --preset paper-1 --plot-step " + path("x.png") + plots, "--plot-step");
    expect_bad_input("analyze --preset paper-1 --dynamics coupled --modulus 5" + plots, "modulus");
}

}  // namespace
