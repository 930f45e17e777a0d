// hmsm analyze's numbers (tools/hmsm/analysis.cpp) on trees whose answers are known, and the
// `hmsm import` / `hmsm analyze` command lines: exit codes, one error line, no partial output.
#include "analysis.h"
#include "cli_fixture.h"
#include "test_trees.h"

#include <nlohmann/json.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <numbers>

using namespace hmsm;
namespace fs = std::filesystem;

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

TEST(Analyze, FitRecoversADampedOscillation) {
    cli::StepResponse r;
    const double f = 0.5, zeta = 0.05, dt = 1.0 / 120.0;
    const double omega = kTwoPi * f / std::sqrt(1 - zeta * zeta);  // natural; damped is f
    for (int k = 1; k <= 120 * 40; ++k) {
        const double t = k * dt;
        r.time.push_back(t);
        r.deflection.push_back(0.3 - 0.3 * std::exp(-zeta * omega * t) * std::cos(kTwoPi * f * t));
    }
    cli::fit_oscillation(r);
    EXPECT_NEAR(r.steady_m, 0.3, 1e-3);
    EXPECT_NEAR(r.frequency_hz, f, 0.005 * f);
    EXPECT_NEAR(r.damping_ratio, zeta, 0.002);
    EXPECT_GE(r.peaks, 10);
}

TEST(Analyze, RodMatchesItsChainConstants) {
    // One chain: a 20 m rod of radius 0.2 m. Its step response is a damped oscillator whose
    // frequency and damping the fit must find, settling at the static angle A s / K.
    const TreeModel rod = test::rod(4, 20.0, 0.2);
    cli::AnalysisSettings s;
    s.parameters.wind_gain = 0.2;
    s.wind_speed = 8.0;
    s.step_seconds = 60.0;
    s.spectrum_seconds = 20.0;
    auto a = cli::analyze_model(rod, "rod", s);
    ASSERT_TRUE(a.ok()) << a.status().message();
    ASSERT_EQ(a->chains.size(), 1u);
    const cli::ChainAnalysis& trunk = a->chains[0];
    const double K = 1e7 * std::pow(0.2, 4) / 20.0, I = 0.2 * 0.2 * 8000.0;
    EXPECT_NEAR(trunk.frequency_hz, std::sqrt(K / I) / kTwoPi, 1e-9);
    EXPECT_NEAR(trunk.damping_ratio, 0.1, 1e-9);
    EXPECT_FALSE(trunk.capped);
    const double strength = (8.0 / 6.0) * (8.0 / 6.0);
    EXPECT_NEAR(a->wind_strength, strength, 1e-12);
    const double angle = 0.2 * 0.2 * 400.0 * strength / K;
    EXPECT_NEAR(trunk.static_angle, angle, 1e-12);
    EXPECT_EQ(a->top_node, 4);
    // Simulated steady state: the top, 20 m up, turned by about the static angle.
    EXPECT_NEAR(a->step.steady_m, 20.0 * std::sin(angle), 0.02 * 20.0 * angle);
    const double damped = trunk.frequency_hz * std::sqrt(1 - 0.01);
    EXPECT_NEAR(a->step.frequency_hz, damped, 0.02 * damped);
    EXPECT_NEAR(a->step.damping_ratio, 0.1, 0.01);
    // Spectrum: one-sided, df = fs / N, all finite and non-negative.
    ASSERT_GT(a->spectrum.frequency_hz.size(), 100u);
    EXPECT_NEAR(a->spectrum.frequency_hz.back(), 60.0, 1e-9);
    for (double p : a->spectrum.power) EXPECT_TRUE(std::isfinite(p) && p >= 0.0);
}

TEST(Analyze, SpectrumPeaksAtTheDrivingOrNaturalFrequency) {
    // Driven by the 'constant' profile the rod rings at its damped natural frequency only; the
    // spectrum of its sway (mean removed) peaks there.
    cli::AnalysisSettings s;
    s.parameters.wind_gain = 0.2;
    s.spectrum_wind.profile = WindProfile::constant;
    s.spectrum_wind.strength = 1.0;
    s.step_seconds = 5.0;
    s.spectrum_seconds = 80.0;
    auto a = cli::analyze_model(test::rod(4, 20.0, 0.2), "rod", s);
    ASSERT_TRUE(a.ok()) << a.status().message();
    const double df = a->spectrum.frequency_hz[0];
    EXPECT_NEAR(a->spectrum.peak_hz, a->chains[0].frequency_hz, 2.0 * df);
}

TEST(Analyze, CapFlagFollowsTheSpecFormula) {
    // A 0.2 m twig of radius 5 mm: raw frequency (1/2pi)(r/L^2)sqrt(k/rho) = 12.6 Hz > 4 Hz.
    Chain twig;
    twig.radius = 0.005, twig.length = 0.2;
    twig.stiffness = 1e7 * std::pow(twig.radius, 4) / twig.length;
    EXPECT_TRUE(cli::chain_capped(twig, Parameters{}));
    Chain trunk;
    trunk.radius = 0.25, trunk.length = 15.0;
    trunk.stiffness = 1e7 * std::pow(trunk.radius, 4) / trunk.length;
    EXPECT_FALSE(cli::chain_capped(trunk, Parameters{}));
    // A large dt lowers f_max to 1 / (4 pi dt): at dt = 0.5 s even the trunk (0.56 Hz) is capped.
    Parameters coarse;
    coarse.dt = 0.5;
    EXPECT_TRUE(cli::chain_capped(trunk, coarse));
    // The library's own flag (what analyze reports) agrees with the formula on every chain.
    auto tree = generate_preset("paper-5");
    ASSERT_TRUE(tree.ok());
    auto hierarchy = build_hierarchy(*tree, ModelOptions{}, Parameters{});
    ASSERT_TRUE(hierarchy.ok());
    int capped = 0;
    for (const Chain& c : hierarchy->chains) {
        EXPECT_EQ(c.capped, cli::chain_capped(c, Parameters{}));
        capped += c.capped;
    }
    EXPECT_GT(capped, 0);
}

// --- the command lines ------------------------------------------------------------------------

class ImportAnalyzeCli : public test::CliFixture {
protected:
    ImportAnalyzeCli() : CliFixture(/*small_tree=*/false) {}
    /// A file of the scratch folder, whole.
    std::string text(const std::string& name) const { return test::read_text(path(name)); }

    const fs::path data_ = fs::path(HMSM_TEST_DATA);
};

TEST_F(ImportAnalyzeCli, ImportWritesATreeAndPrintsWhatItRead) {
    ASSERT_EQ(run("import --treeqsm " + (data_ / "import" / "scan_treeqsm_v23.txt").string() + " --out " +
                  path("t.json") + " --leaves 120 --leaf-seed 3 --json").exit_code,
              0)
        << last_.err;
    auto summary = nlohmann::json::parse(last_.out);
    EXPECT_EQ(summary["format"], "treeqsm-v2.3");
    EXPECT_EQ(summary["cylinders"], 230);
    EXPECT_EQ(summary["leaves"], 120);
    EXPECT_NEAR(summary["height_m"].get<double>(), 16.116, 2e-3);
    EXPECT_DOUBLE_EQ(summary["trunk_base_radius_m"].get<double>(), 0.24);
    auto tree = load_tree(path("t.json"));
    ASSERT_TRUE(tree.ok()) << tree.status().message();
    EXPECT_EQ(tree->leaves.size(), 120u);
    EXPECT_EQ(tree->nodes.size(), summary["nodes"].get<size_t>());
}

TEST_F(ImportAnalyzeCli, ImportRejectsBadFilesAndFlagsWithoutOutput) {
    const std::string bad = (data_ / "bad" / "treeqsms" / "cycle.txt").string();
    expect_bad_input("import --treeqsm " + bad + " --out " + path("t.json"), "line 3: cylinder is in a cycle");
    expect_bad_input("import --simpleforest " + (data_ / "bad" / "simpleforests" / "zero_radius.csv").string() +
                         " --out " + path("t.json"),
                     "line 3: radius must be > 0");
    expect_bad_input("import --out " + path("t.json"), "--treeqsm FILE or --simpleforest FILE");
    const std::string good = (data_ / "import" / "scan_treeqsm.txt").string();
    expect_bad_input("import --treeqsm " + good + " --simpleforest " + good + " --out " + path("t.json"), "excludes");
    expect_bad_input("import --treeqsm " + good + " --out " + path("t.json") + " --leaves 5 --leaf-size 0 0.1",
                     "leaf size");
    expect_bad_input("import --treeqsm " + path("missing.txt") + " --out " + path("t.json"), "cannot open");
}

TEST_F(ImportAnalyzeCli, AnalyzeWritesNumbersAndPlots) {
    ASSERT_EQ(run("import --simpleforest " + (data_ / "import" / "scan_simpleforest.csv").string() + " --out " +
                  path("t.json")).exit_code,
              0);
    ASSERT_EQ(run("analyze --tree " + path("t.json") + " --step-seconds 20 --spectrum-seconds 20 --json" +
                  " --plot-step " + path("step.png") + " --plot-spectrum " + path("spectrum.png") +
                  " --plot-chains " + path("chains.png")).exit_code,
              0)
        << last_.err;
    auto j = nlohmann::json::parse(last_.out);
    ASSERT_EQ(j["models"].size(), 1u);
    const auto& m = j["models"][0];
    auto tree = load_tree(path("t.json"));
    ASSERT_TRUE(tree.ok());
    auto h = build_hierarchy(*tree, {});
    ASSERT_TRUE(h.ok());
    ASSERT_EQ(m["chains"].size(), h->chains.size());
    const Chain& trunk = h->chains[0];
    EXPECT_NEAR(m["trunk_frequency_hz"].get<double>(), std::sqrt(trunk.stiffness / trunk.inertia) / kTwoPi, 1e-9);
    EXPECT_GT(m["top_static_deflection_m"].get<double>(), 0.0);
    EXPECT_GE(m["step_response"]["peaks_fitted"].get<int>(), 2);
    for (const char* png : {"step.png", "spectrum.png", "chains.png"}) {
        const std::string bytes = text(png);
        ASSERT_GT(bytes.size(), 1000u) << png;
        EXPECT_EQ(bytes.substr(1, 3), "PNG") << png;
    }
    // Text output names the trunk frequency too.
    ASSERT_EQ(run("analyze --preset paper-5 --step-seconds 2 --spectrum-seconds 2").exit_code, 0) << last_.err;
    EXPECT_NE(last_.out.find("trunk natural frequency"), std::string::npos);
}

TEST_F(ImportAnalyzeCli, AnalyzeRejectsBadInputWithoutPlots) {
    const std::string plots = " --plot-step " + path("s.png") + " --plot-chains " + path("c.png");
    expect_bad_input("analyze --preset paper-5 --wind-speed -1" + plots, "--wind-speed");
    expect_bad_input("analyze --preset paper-5 --step-seconds 0" + plots, "--step-seconds");
    expect_bad_input("analyze --preset paper-5 --wind-strength 2" + plots, "--wind-speed");
    expect_bad_input("analyze --preset nope" + plots, "nope");
    expect_bad_input("analyze" + plots, "--tree FILE or --preset NAME");
    expect_bad_input("analyze --preset paper-5 --dt 0" + plots, "dt");
}

}  // namespace
