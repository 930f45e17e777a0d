// hmsm analyze --whole-tree (see tree_response.h): per model the release test's f0 and damping
// ratio and, per --sway-speeds, the atmospheric sway's spectrum slope above f0, cross-wind ratio,
// mean base lean and mean top displacement over the height. Text or JSON on stdout; PNG plots with
// --plot-release and --plot-sway.
#include "cmd_analyze_tree.h"

#include "step_progress.h"
#include "tree_response.h"
#ifdef HMSM_HAVE_PLOTS
#include "plot.h"
#endif

#include <nlohmann/json.hpp>

#include <cmath>
#include <numbers>

namespace hmsm::cli {
namespace {

struct WholeTreeFlags {
    bool on = false;
    TreeResponseSettings settings;
    std::string plot_release, plot_sway;
} flags;

nlohmann::json to_json(const TreeResponse& r, const ModelOptions& options, const Parameters& p) {
    nlohmann::json j;
    j["model"] = r.name;
    j["dynamics"] = to_string(options.dynamics);
    if (options.dynamics == Dynamics::coupled) j["exchange"] = to_string(options.exchange);
    j["leaves_on"] = p.foliage.on;
    j["modulus_pa"] = p.material.modulus;
    j["wood_density_kg_m3"] = p.material.density;
    j["nodes"] = r.nodes;
    j["height_m"] = r.height;
    j["dbh_m"] = r.dbh;
    j["top_node"] = r.top_node;
    j["base_node"] = r.base_node;
    j["release"] = {{"pulled_m", r.release.pulled_m},
                    {"frequency_hz", r.release.frequency_hz},
                    {"fft_frequency_hz", r.release.fft_frequency_hz},
                    {"damping_ratio", r.release.damping_ratio},
                    {"cycles", r.release.cycles},
                    {"method", "upward zero crossings; logarithmic decrement of the peak per cycle"}};
    nlohmann::json sway = nlohmann::json::array();
    for (const SwayRun& s : r.sway)
        sway.push_back({{"speed_m_s", s.speed},
                        {"strength", s.strength},
                        {"slope", s.slope},
                        {"slope_band_hz", {s.band_low_hz, s.band_high_hz}},
                        {"slope_bins", s.band_bins},
                        {"mean_along_m", s.mean_along_m},
                        {"rms_along_m", s.rms_along_m},
                        {"rms_cross_m", s.rms_cross_m},
                        {"cross_ratio", s.cross_ratio},
                        {"mean_lean_deg", s.mean_lean_rad * 180.0 / std::numbers::pi},
                        {"mean_top_over_height", s.mean_top_over_height}});
    j["sway"] = std::move(sway);
    if (r.links) {
        const LinkModesReport& l = *r.links;
        nlohmann::json along = nlohmann::json::array(), across = nlohmann::json::array();
        for (const auto& share : l.mass_share) {
            along.push_back(share[0]);
            across.push_back(share[1]);
        }
        j["linearized_links"] = {{"modes_hz", l.frequency_hz},
                                 {"mass_share_along", along},
                                 {"mass_share_across", across},
                                 {"sway_along_hz", l.sway_hz[0]},
                                 {"sway_across_hz", l.sway_hz[1]},
                                 {"trunk_f0_hz", l.trunk_f0_hz},
                                 {"converged", l.converged}};
    }
    return j;
}

void print_text(const TreeResponse& r, const Parameters& p, const ModelOptions& options) {
    const TreeResponseSettings& s = flags.settings;
    const Dynamics dynamics = options.dynamics;
    const bool coupled = dynamics == Dynamics::coupled;
    std::printf("model %s (%s dynamics%s%s%s): %zu nodes, height %.3f m, DBH %.3f m, top node %d\n", r.name.c_str(),
                to_string(dynamics), coupled ? ", exchange " : "", coupled ? to_string(options.exchange) : "",
                coupled ? (p.foliage.on ? ", leaves on" : ", leaves off") : "", r.nodes, r.height, r.dbh, r.top_node);
    if (dynamics == Dynamics::coupled)
        std::printf("wood           E %.3g Pa, density %.4g kg/m^3, structural damping %.3g\n", p.material.modulus,
                    p.material.density, p.structural_damping);
    std::printf("release test   pulled %.4f m by %.1f m/s for %.0f s, decay over %.0f s\n", r.release.pulled_m,
                s.pull_speed, s.pull_seconds, s.release_seconds);
    if (r.release.cycles > 0)
        std::printf("  f0           %.4f Hz (zero crossings, %d cycles); spectrum peak %.4f Hz\n",
                    r.release.frequency_hz, r.release.cycles, r.release.fft_frequency_hz);
    else
        std::printf("  f0           no oscillation (fewer than 3 crossings); spectrum peak %.4f Hz\n",
                    r.release.fft_frequency_hz);
    std::printf("  damping      %.4f (logarithmic decrement)\n", r.release.damping_ratio);
    std::printf("speed_m_s  slope   band_hz        cross/along  lean_deg  top/H     rms_along_m\n");
    for (const SwayRun& w : r.sway)
        std::printf("%9.1f  %6.2f  %5.3f-%-7.3f  %11.3f  %8.3f  %.5f  %.5f\n", w.speed, w.slope, w.band_low_hz,
                    w.band_high_hz, w.cross_ratio, w.mean_lean_rad * 180.0 / std::numbers::pi,
                    w.mean_top_over_height, w.rms_along_m);
    if (!r.links) return;
    const LinkModesReport& l = *r.links;
    std::printf("linearized links (all joints coupled, rest pose)%s\n", l.converged ? "" : " (not converged)");
    std::printf("  sway         %.4f Hz along the wind, %.4f Hz across (trunk chain's own f0 %.4f / %.4f Hz)\n",
                l.sway_hz[0], l.sway_hz[1], l.trunk_f0_hz[0], l.trunk_f0_hz[1]);
    std::printf("  mode  f_hz     mass share along  across\n");
    for (size_t k = 0; k < l.frequency_hz.size(); ++k)
        std::printf("  %4zu  %-8.4f %-17.4f %.4f\n", k + 1, l.frequency_hz[k], l.mass_share[k][0], l.mass_share[k][1]);
}

#ifdef HMSM_HAVE_PLOTS
Status write_plots(const TreeResponse& r, StagedOutputs& outputs, int release_index, int sway_index) {
    if (release_index >= 0) {
        plot::Series trace{r.release.time, r.release.displacement, plot::palette(0), "trunk top"};
        char title[200];
        std::snprintf(title, sizeof title, "Release test of %s: f0 %.3f Hz, damping %.3f", r.name.c_str(),
                      r.release.frequency_hz, r.release.damping_ratio);
        auto png = plot::line_chart_png({title, "time after release (s)", "top displacement along the wind (m)"}, {trace});
        if (!png) return png.status();
        HMSM_TRY(outputs.write(size_t(release_index), png->data(), png->size()));
    }
    if (sway_index >= 0 && !r.sway.empty()) {
        std::vector<plot::Series> series;
        double top = 0;
        for (const SwayRun& w : r.sway)
            for (double v : w.along.power) top = std::max(top, v);
        const double bottom = top * 1e-10;
        for (size_t i = 0; i < r.sway.size(); ++i) {
            const SwayRun& w = r.sway[i];
            char label[64];
            std::snprintf(label, sizeof label, "%.0f m/s, slope %.2f", w.speed, w.slope);
            plot::Series psd{{}, {}, plot::palette(i), label};
            for (size_t k = 0; k < w.along.power.size(); ++k)
                if (w.along.frequency_hz[k] <= 2.0 * w.band_high_hz) {
                    psd.x.push_back(w.along.frequency_hz[k]);
                    psd.y.push_back(std::max(w.along.power[k], bottom));
                }
            series.push_back(std::move(psd));
        }
        // The -3 slope of measured trees, through the first run's power at the band's start.
        const SwayRun& w = r.sway[0];
        double anchor = 0;
        for (size_t k = 0; k < w.along.power.size(); ++k)
            if (w.along.frequency_hz[k] >= w.band_low_hz) { anchor = w.along.power[k]; break; }
        if (anchor > 0)
            series.push_back({{w.band_low_hz, w.band_high_hz},
                              {anchor, anchor * std::pow(w.band_high_hz / w.band_low_hz, -3.0)},
                              plot::palette(7), "slope -3"});
        auto png = plot::line_chart_png({"Along-wind sway spectrum of " + r.name + " (atmospheric wind)",
                                         "frequency (Hz)", "PSD (m^2/Hz)", true, true}, series);
        if (!png) return png.status();
        HMSM_TRY(outputs.write(size_t(sway_index), png->data(), png->size()));
    }
    return {};
}
#endif

}  // namespace

void register_whole_tree_flags(CLI::App& app) {
    TreeResponseSettings& s = flags.settings;
    app.add_flag("--whole-tree", flags.on,
                 "whole-tree report instead of per chain: release test (f0, damping) and atmospheric sway");
    app.add_option("--pull-speed", s.pull_speed, "--whole-tree: constant wind (m/s) that bends the tree (default 10)");
    app.add_option("--pull-seconds", s.pull_seconds, "--whole-tree: how long it pulls before release (default 20)");
    app.add_option("--release-seconds", s.release_seconds, "--whole-tree: free decay recorded (default 60)");
    app.add_option("--sway-speeds", s.sway_speeds, "--whole-tree: atmospheric wind speeds in m/s (default 5,10,20)")
        ->delimiter(',');
    app.add_option("--sway-seconds", s.sway_seconds, "--whole-tree: sway recorded per speed (default 120)");
    app.add_option("--settle-seconds", s.settle_seconds, "--whole-tree: sway not recorded at the start (default 20)");
    app.add_option("--plot-release", flags.plot_release, "--whole-tree PNG: the release test's decay");
    app.add_option("--plot-sway", flags.plot_sway, "--whole-tree PNG: the sway spectra (log-log)");
}

bool whole_tree_requested() { return flags.on; }

int run_whole_tree(const Scene& scene, const ModelOptions& options, const Parameters& parameters, const Wind& wind,
                   StagedOutputs& outputs, bool json, bool progress) {
    TreeResponseSettings settings = flags.settings;
    settings.options = options;
    settings.parameters = parameters;
    settings.wind_direction = wind.direction;
    settings.turbulence = wind.turbulence;
    settings.seed = wind.seed;
    int release_index = -1, sway_index = -1;
    const std::pair<const std::string*, const char*> plots[] = {{&flags.plot_release, "--plot-release"},
                                                                {&flags.plot_sway, "--plot-sway"}};
    for (int k = 0; k < 2; ++k) {
        if (plots[k].first->empty()) continue;
#ifndef HMSM_HAVE_PLOTS
        return fail_input(std::string(plots[k].second) + ": this hmsm was built without libpng and stb (no plots)");
#endif
        auto staged = outputs.stage(*plots[k].first, plots[k].second);
        if (!staged) return fail(staged.status());
        (k == 0 ? release_index : sway_index) = int(*staged);
    }
    const double dt = parameters.dt;
    const bool counted = std::isfinite(dt) && dt > 0.0 && settings.pull_seconds <= 3600 &&
                         settings.release_seconds <= 3600 && settings.sway_seconds <= 3600 &&
                         settings.settle_seconds <= 3600 && settings.sway_speeds.size() <= 16;
    const uint64_t per_model =
        counted ? uint64_t(std::ceil(settings.pull_seconds / dt)) + uint64_t(std::ceil(settings.release_seconds / dt)) +
                      settings.sway_speeds.size() * (uint64_t(std::ceil(settings.settle_seconds / dt)) +
                                                     uint64_t(std::ceil(settings.sway_seconds / dt)))
                : 0;
    StepProgress bar(per_model * scene.models.size(), progress && counted);
    uint64_t done = 0;
    settings.on_step = [&] { bar.update(++done); };
    std::vector<TreeResponse> responses;
    for (size_t m = 0; m < scene.models.size(); ++m) {
        auto r = analyze_tree_response(scene.models[m], scene.model_names[m], settings);
        if (!r) {
            bar.finish();
            return fail(r.status());
        }
        responses.push_back(std::move(r).value());
    }
    bar.finish();
#ifdef HMSM_HAVE_PLOTS
    Status plotted = write_plots(responses[0], outputs, release_index, sway_index);
    if (!plotted) return fail(plotted);
#endif
    Status committed = outputs.commit();
    if (!committed) return fail(committed);
    if (json) {
        nlohmann::json j;
        j["models"] = nlohmann::json::array();
        for (size_t m = 0; m < responses.size(); ++m)
            j["models"].push_back(
                to_json(responses[m], options, parameters_for_tree(scene.models[m], parameters)));
        std::printf("%s\n", j.dump(2).c_str());
    } else {
        for (size_t m = 0; m < responses.size(); ++m) {
            if (m) std::printf("\n");
            print_text(responses[m], parameters_for_tree(scene.models[m], parameters), options);
        }
    }
    return kExitOk;
}

}  // namespace hmsm::cli
