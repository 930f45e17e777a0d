// hmsm analyze (--tree FILE | --preset NAME | --forest FILE): how a tree will sway. Per chain its
// natural frequency, damping ratio, whether the frequency cap raised it and its static deflection
// at --wind-speed; the top node's step response (constant wind switched on at t = 0) with its
// measured frequency and damping, and the power spectrum of its sway under a chosen wind.
// Text or JSON on stdout; PNG plots with --plot-step, --plot-spectrum, --plot-chains. With
// --whole-tree, the whole-tree report of cmd_analyze_tree.cpp instead.
#include "analysis.h"
#include "cli_common.h"
#include "cmd_analyze_tree.h"
#include "step_progress.h"
#ifdef HMSM_HAVE_PLOTS
#include "plot.h"
#endif

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>

namespace hmsm::cli {
namespace {
struct AnalyzeFlags {
    SourceFlags source;
    ModelFlags model;
    Parameters parameters;
    WindFlags wind;  // the spectrum's wind (its strength follows --wind-speed)
    double wind_speed = 6.0;
    std::string wind_dir = "1,0,0";
    double step_seconds = 30.0, spectrum_seconds = 60.0;
    bool json = false, no_progress = false;
    std::string plot_step, plot_spectrum, plot_chains;
    bool shared_speed = false;  // --wind-speed was registered by add_wind_flags
} flags;

double median(std::vector<double> v) {
    if (v.empty()) return 0;
    std::sort(v.begin(), v.end());
    return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

nlohmann::json to_json(const ModelAnalysis& m, double speed) {
    nlohmann::json j;
    j["model"] = m.name;
    j["nodes"] = m.nodes;
    j["height_m"] = m.height;
    j["top_node"] = m.top_node;
    j["wind_speed_m_s"] = speed;
    j["wind_strength"] = m.wind_strength;
    j["trunk_frequency_hz"] = m.chains[0].frequency_hz;
    j["trunk_damping_ratio"] = m.chains[0].damping_ratio;
    j["capped_chains"] = std::count_if(m.chains.begin(), m.chains.end(), [](const auto& c) { return c.capped; });
    j["top_static_deflection_m"] = m.step.steady_m;
    j["top_static_deflection_method"] = "simulated: constant wind to steady state (mean of the last quarter of the step run)";
    j["step_response"] = {{"seconds", m.step.time.empty() ? 0.0 : m.step.time.back()},
                          {"measured_frequency_hz", m.step.frequency_hz},
                          {"measured_damping_ratio", m.step.damping_ratio},
                          {"peaks_fitted", m.step.peaks}};
    j["spectrum_peak_hz"] = m.spectrum.peak_hz;
    nlohmann::json chains = nlohmann::json::array();
    for (const ChainAnalysis& c : m.chains)
        chains.push_back({{"chain", c.chain}, {"parent", c.parent}, {"depth", c.depth}, {"length_m", c.length},
                          {"radius_m", c.radius}, {"frequency_hz", c.frequency_hz},
                          {"damping_ratio", c.damping_ratio}, {"capped", c.capped},
                          {"static_angle_rad", c.static_angle}, {"static_tip_m", c.static_tip_m}});
    j["chains"] = std::move(chains);
    return j;
}

void print_text(const ModelAnalysis& m, double speed, const Wind& spectrum_wind, double spectrum_seconds) {
    const ChainAnalysis& trunk = m.chains[0];
    const auto capped = std::count_if(m.chains.begin(), m.chains.end(), [](const auto& c) { return c.capped; });
    std::printf("model %s: %zu nodes, %zu chains, height %.3f m\n", m.name.c_str(), m.nodes, m.chains.size(), m.height);
    std::printf("trunk natural frequency   %.4f Hz (damping ratio %.3f, length %.3f m, radius %.4f m)\n",
                trunk.frequency_hz, trunk.damping_ratio, trunk.length, trunk.radius);
    std::printf("capped chains             %td of %zu (f_cap %.3g Hz, docs/model.md 3.4)\n", capped,
                m.chains.size(), flags.parameters.max_frequency);
    std::printf("wind                      %.2f m/s = strength %.4f\n", speed, m.wind_strength);
    std::printf("trunk static angle        %.6f rad (A s / K)\n", trunk.static_angle);
    std::printf("top node %-6d deflection %.6f m (simulated: constant wind to steady state)\n", m.top_node,
                m.step.steady_m);
    if (m.step.peaks >= 2)
        std::printf("step response             measured %.4f Hz, damping ratio %.3f (fit to %d peaks over %.1f s)\n",
                    m.step.frequency_hz, m.step.damping_ratio, m.step.peaks, m.step.time.back());
    else
        std::printf("step response             no oscillation to fit (fewer than 2 peaks over %.1f s)\n",
                    m.step.time.empty() ? 0.0 : m.step.time.back());
    std::printf("spectrum                  peak at %.4f Hz (%s wind, %.0f s)\n", m.spectrum.peak_hz,
                to_string(spectrum_wind.profile), spectrum_seconds);
    std::printf("depth  chains  f_min_hz  f_median_hz  f_max_hz  capped\n");
    int32_t depths = 0;
    for (const auto& c : m.chains) depths = std::max(depths, c.depth + 1);
    for (int32_t d = 0; d < depths; ++d) {
        std::vector<double> f;
        int n_capped = 0;
        for (const auto& c : m.chains)
            if (c.depth == d) f.push_back(c.frequency_hz), n_capped += c.capped;
        if (f.empty()) continue;
        std::printf("%5d  %6zu  %8.4f  %11.4f  %8.4f  %6d\n", d, f.size(), *std::min_element(f.begin(), f.end()),
                    median(f), *std::max_element(f.begin(), f.end()), n_capped);
    }
    if (m.chains.size() <= 24) {
        std::printf("chain parent depth  length_m  radius_m  f_hz     zeta   capped  angle_rad\n");
        for (const auto& c : m.chains)
            std::printf("%5d %6d %5d  %8.3f  %8.4f  %7.4f  %5.3f  %-6s  %.6f\n", c.chain, c.parent, c.depth, c.length,
                        c.radius, c.frequency_hz, c.damping_ratio, c.capped ? "yes" : "no", c.static_angle);
    } else {
        std::printf("(%zu chains: --json lists every chain)\n", m.chains.size());
    }
}

#ifdef HMSM_HAVE_PLOTS
Status write_plots(const ModelAnalysis& m, StagedOutputs& outputs, const std::vector<std::pair<size_t, int>>& files,
                   const Wind& spectrum_wind) {
    for (auto [index, kind] : files) {
        Result<std::vector<uint8_t>> png = std::vector<uint8_t>{};
        if (kind == 0) {
            plot::Series trace{m.step.time, m.step.deflection, plot::palette(0), "top node"};
            plot::Series steady{{m.step.time.front(), m.step.time.back()}, {m.step.steady_m, m.step.steady_m},
                                plot::palette(7), "steady state"};
            char title[160];
            std::snprintf(title, sizeof title, "Step response of %s: %.3f Hz, damping %.3f", m.name.c_str(),
                          m.step.frequency_hz, m.step.damping_ratio);
            png = plot::line_chart_png({title, "time (s)", "top deflection along the wind (m)"}, {trace, steady});
        } else if (kind == 1) {
            // Up to 20 Hz and ten decades below the peak: the rest is rounding noise.
            double top = 0;
            for (double v : m.spectrum.power) top = std::max(top, v);
            const double bottom = top * 1e-10;
            plot::Series psd{{}, {}, plot::palette(0), "top node sway"};
            for (size_t k = 0; k < m.spectrum.power.size(); ++k)
                if (m.spectrum.frequency_hz[k] <= 20.0) {
                    psd.x.push_back(m.spectrum.frequency_hz[k]);
                    psd.y.push_back(std::max(m.spectrum.power[k], bottom));
                }
            const double f0 = m.chains[0].frequency_hz;
            plot::Series mark{{f0, f0}, {bottom, top}, plot::palette(1), "trunk natural frequency"};
            std::string title = "Sway spectrum of " + m.name + " (" + to_string(spectrum_wind.profile) + " wind)";
            png = plot::line_chart_png({title, "frequency (Hz)", "PSD (m^2/Hz)", true, true}, {psd, mark});
        } else {
            double f_hi = 0;
            int32_t depths = 0;
            for (const auto& c : m.chains) f_hi = std::max(f_hi, c.frequency_hz), depths = std::max(depths, c.depth + 1);
            plot::Stacks stacks;
            const int bins = 40;
            f_hi = f_hi > 0 ? f_hi * 1.02 : 1.0;
            for (int k = 0; k <= bins; ++k) stacks.edges.push_back(f_hi * k / bins);
            stacks.layers.assign(size_t(depths), std::vector<double>(bins, 0.0));
            for (const auto& c : m.chains)
                stacks.layers[size_t(c.depth)][size_t(std::min(bins - 1, int(c.frequency_hz / f_hi * bins)))] += 1;
            for (int32_t d = 0; d < depths; ++d) stacks.labels.push_back("depth " + std::to_string(d));
            png = plot::stacked_histogram_png({"Chain natural frequencies of " + m.name, "frequency (Hz)", "chains"},
                                              stacks);
        }
        if (!png) return png.status();
        HMSM_TRY(outputs.write(index, png->data(), png->size()));
    }
    return {};
}
#else
Status write_plots(const ModelAnalysis&, StagedOutputs&, const std::vector<std::pair<size_t, int>>&, const Wind&) {
    return {};  // no plot was staged: run_analyze refuses the flags in this build
}
#endif

}  // namespace

void register_analyze_flags(CLI::App& app) {
    add_source_flags(app, flags.source, true);
    add_model_flags(app, flags.model);
    add_parameter_flags(app, flags.parameters);
    add_wind_flags(app, flags.wind);
    // Simulate's wind flags may define --wind-speed themselves; then run_analyze reads it there.
    if (!app.get_option_no_throw("--wind-speed"))
        app.add_option("--wind-speed", flags.wind_speed,
                       "wind speed in m/s for static deflection, step response and spectrum (default 6: strength 1)");
    else
        flags.shared_speed = true;
    app.add_option("--step-seconds", flags.step_seconds, "length of the step-response run (default 30)");
    app.add_option("--spectrum-seconds", flags.spectrum_seconds, "length of the spectrum run (default 60)");
    app.add_flag("--json", flags.json, "print JSON instead of text");
    app.add_flag("--no-progress", flags.no_progress, "no progress on stderr");
    app.add_option("--plot-step", flags.plot_step, "PNG: the top node's step response");
    app.add_option("--plot-spectrum", flags.plot_spectrum, "PNG: the top node's sway spectrum (log-log)");
    app.add_option("--plot-chains", flags.plot_chains, "PNG: histogram of chain frequencies by depth");
    register_whole_tree_flags(app);
}

int run_analyze(CLI::App& app) {
    if (app.count("--wind-strength"))
        return fail_input("analyze takes the wind as --wind-speed (m/s), not --wind-strength");
    if (flags.shared_speed && app.count("--wind-speed")) flags.wind_speed = app["--wind-speed"]->as<double>();
    auto options = model_options(flags.model);
    if (!options) return fail(options.status());
    auto wind = wind_options(flags.wind);
    if (!wind) return fail(wind.status());
    auto scene = load_scene(flags.source, app);
    if (!scene) return fail(scene.status());
    AnalysisSettings settings;
    settings.options = *options;
    settings.parameters = flags.parameters;
    settings.wind_speed = flags.wind_speed;
    settings.wind_direction = wind->direction;
    settings.step_seconds = flags.step_seconds;
    settings.spectrum_seconds = flags.spectrum_seconds;
    settings.spectrum_wind = *wind;
    settings.spectrum_wind.strength = strength_of_speed(flags.wind_speed);
    StagedOutputs outputs;
    outputs.add_inputs({flags.source.tree, flags.source.forest, flags.wind.schedule});
    if (whole_tree_requested()) {
        for (const char* chain_flag : {"--plot-step", "--plot-spectrum", "--plot-chains", "--step-seconds",
                                       "--spectrum-seconds"})
            if (app.count(chain_flag))
                return fail_input(std::string(chain_flag) + " belongs to the per-chain report, not --whole-tree");
        Status valid = validate(flags.parameters);
        if (!valid) return fail(valid);
        return run_whole_tree(*scene, *options, flags.parameters, *wind, outputs, flags.json, !flags.no_progress);
    }
    std::vector<std::pair<size_t, int>> files;
    const std::pair<const std::string*, const char*> plots[] = {
        {&flags.plot_step, "--plot-step"}, {&flags.plot_spectrum, "--plot-spectrum"}, {&flags.plot_chains, "--plot-chains"}};
    for (int k = 0; k < 3; ++k) {
        if (plots[k].first->empty()) continue;
#ifndef HMSM_HAVE_PLOTS
        return fail_input(std::string(plots[k].second) + ": this hmsm was built without libpng and stb (no plots)");
#endif
        auto staged = outputs.stage(*plots[k].first, plots[k].second);
        if (!staged) return fail(staged.status());
        files.emplace_back(*staged, k);
    }
    // Both runs (step response, spectrum) of every model, as trace_top counts their steps.
    const double dt = settings.parameters.dt;
    const bool counted = std::isfinite(dt) && dt > 0.0 && settings.step_seconds <= 3600 &&
                         settings.spectrum_seconds <= 3600;
    const uint64_t steps_per_model =
        counted ? uint64_t(std::ceil(settings.step_seconds / dt)) + uint64_t(std::ceil(settings.spectrum_seconds / dt))
                : 0;
    StepProgress progress(steps_per_model * scene->models.size(), !flags.no_progress && counted);
    uint64_t steps_done = 0;
    settings.on_step = [&] { progress.update(++steps_done); };
    std::vector<ModelAnalysis> analyses;
    for (size_t m = 0; m < scene->models.size(); ++m) {
        auto analysis = analyze_model(scene->models[m], scene->model_names[m], settings);
        if (!analysis) {
            progress.finish();
            return fail(analysis.status());
        }
        analyses.push_back(std::move(analysis).value());
    }
    progress.finish();
    // Plots show the first model (the tree, or the forest's first).
    Status plotted = write_plots(analyses[0], outputs, files, settings.spectrum_wind);
    if (!plotted) return fail(plotted);
    Status committed = outputs.commit();
    if (!committed) return fail(committed);
    if (flags.json) {
        nlohmann::json j;
        j["models"] = nlohmann::json::array();
        for (const auto& a : analyses) j["models"].push_back(to_json(a, flags.wind_speed));
        std::printf("%s\n", j.dump(2).c_str());
    } else {
        for (size_t m = 0; m < analyses.size(); ++m) {
            if (m) std::printf("\n");
            print_text(analyses[m], flags.wind_speed, settings.spectrum_wind, settings.spectrum_seconds);
        }
    }
    return kExitOk;
}

}  // namespace hmsm::cli
