// hmsm bench --open-world: the flags' settings and the markdown tables (bench_open_world.h).
#include "bench_open_world.h"

#include <cmath>
#include <cstdio>

namespace hmsm::cli::bench {

using nlohmann::json;

Result<OpenWorldSettings> open_world_settings(int64_t trees, int64_t frames, int64_t changes, bool changes_given,
                                              int64_t fade_steps, double fade_bound_m) {
    auto bad = [](const std::string& message) { return Status{ErrorCode::invalid_argument, message}; };
    if (trees < 1 || trees > kMaxInstances)
        return bad("--open-world-trees " + std::to_string(trees) + ": must be in [1, " + std::to_string(kMaxInstances) + "]");
    if (frames < 1 || frames > 100000)
        return bad("--open-world-frames " + std::to_string(frames) + ": must be in [1, 100000]");
    if (changes_given && (changes < 1 || changes > trees))
        return bad("--open-world-changes " + std::to_string(changes) + ": must be in [1, --open-world-trees]");
    if (fade_steps < 0 || fade_steps > int64_t(kMaxLodFadeSteps))
        return bad("--open-world-fade-steps " + std::to_string(fade_steps) + ": must be in [0, " +
                   std::to_string(kMaxLodFadeSteps) + "]");
    if (!(fade_bound_m >= 0.0 && fade_bound_m <= 1.0))
        return bad("--open-world-fade-bound " + std::to_string(fade_bound_m) + ": must be in [0, 1] (metres)");
    OpenWorldSettings settings;
    settings.fade_steps = uint32_t(fade_steps);
    settings.fade_bound_m = fade_bound_m;
    settings.trees = uint32_t(trees);
    settings.frames = uint32_t(frames);
    settings.changes = changes_given ? uint32_t(changes)
                                     : uint32_t(std::max<int64_t>(1, std::llround(2000.0 * double(trees) / 500000.0)));
    return settings;
}

std::string render_open_world(const json& rows) {
    if (!rows.is_array() || rows.empty()) return "";
    std::string out =
        "\n### Open world: trees streamed around a moving viewer, levels by distance\n\n"
        "Joints only. Room for twice each level's share of the trees is reserved before they stream in "
        "(`reserve_instances` by level). Per frame: swap-remove the trees that left the radius, add those that came, "
        "`update_lod(viewer)`, one `step`. Frame: the four calls; standing still: the same frames "
        "with the viewer at rest (update_lod and step), timed once the fades begun while moving have ended; changes add: frame median moving minus standing "
        "still. Pop: the largest vertex jump of a switched tree (skinned from its joint matrices) "
        "against that tree's motion over the frame before; coarsening fades over the steps given "
        "(`fade`, 0: instantaneous switches; a tree at rest switches at once only where the JSON's "
        "`fade_bound_m` is above 0, measured with a read). % copy: passes 1-5 bytes per step over "
        "the standing step's median, against the copy roofline.\n\n"
        "| backend | trees | chains | changes per frame | step ms (still) | frame ms median / p99 / max | "
        "changes add ms | calls > 1 ms | fade | pop mm (motion mm) | % copy | memory GB (whole trees) |\n"
        "|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|\n";
    char line[600];
    auto seconds_of = [](const json& d, const char* key) {
        return d.is_object() && d.contains(key) ? d[key].get<double>() * 1e3 : 0.0;
    };
    std::string calls_table, passes_table;
    for (const json& r : rows) {
        const std::string backend = r.value("backend", std::string());
        if (r.contains("skipped") || r.contains("failed")) {
            const json memory = r.value("memory", json::object());
            std::snprintf(line, sizeof line, "%.2f (%.1f)", memory.value("estimate_device_bytes", 0.0) * 1e-9,
                          memory.value("estimate_whole_trees_device_bytes", 0.0) * 1e-9);
            out += "| " + backend + " | " + std::to_string(r.value("trees_asked", 0ull)) + " | – | – | – | " +
                   r.value("skipped", r.value("failed", std::string())) + " | | | | | | " +
                   (memory.empty() ? std::string() : std::string(line)) + " |\n";
            continue;
        }
        const json calls = r.value("calls", json::object()), still = r.value("still", json::object());
        const json frame = calls.value("frame", json::object()), pop = r.value("pop", json::object());
        const json memory = r.value("memory", json::object());
        uint64_t over = 0;
        for (const auto& [name, d] : calls.items())
            if (name != "frame") over += d.value("over_1ms", 0ull);
        std::snprintf(line, sizeof line,
                      "| %s | %llu | %llu | %.0f | %.3f | %.3f / %.3f / %.3f | %.3f | %llu | %llu | %.3g (%.3g) | %.1f | "
                      "%.2f (%.1f) |\n",
                      backend.c_str(), (unsigned long long)r.value("instances", 0ull),
                      (unsigned long long)r.value("chains", 0ull),
                      r.value("changes_per_frame", json::object()).value("median", 0.0),
                      seconds_of(still.value("step", json::object()), "median_seconds"),
                      seconds_of(frame, "median_seconds"), seconds_of(frame, "p99_seconds"),
                      seconds_of(frame, "max_seconds"), r.value("changes_add_seconds", 0.0) * 1e3,
                      (unsigned long long)over, (unsigned long long)r.value("fade_steps", 0ull),
                      pop.value("largest_jump_m", 0.0) * 1e3,
                      pop.value("motion_of_largest_m", 0.0) * 1e3, r.value("copy_bandwidth_fraction", 0.0) * 100.0,
                      memory.value("estimate_device_bytes", 0.0) * 1e-9,
                      memory.value("estimate_whole_trees_device_bytes", 0.0) * 1e-9);
        out += line;
        const json passes = r.value("still_pass_seconds", json::object());
        if (!passes.empty()) {
            std::string cells;
            for (const auto& [name, seconds] : passes.items()) {
                std::snprintf(line, sizeof line, "%s%s %.3f", cells.empty() ? "" : ", ", name.c_str(),
                              seconds.get<double>() * 1e3);
                cells += line;
            }
            std::string engine;
            for (const json& e : r.value("still_engine", json::array())) {
                std::snprintf(line, sizeof line, "%s%s %.3f / %.3f", engine.empty() ? "" : ", ",
                              e.value("path", std::string()).c_str(), e.value("call_median_seconds", 0.0) * 1e3,
                              e.value("frame_median_seconds", 0.0) * 1e3);
                engine += line;
            }
            passes_table += "| " + backend + " | " + std::to_string(r.value("groups", 0ull)) + " | " +
                            std::to_string(r.value("dispatches_per_step", 0ull)) + " | " + cells + " | " + engine +
                            " |\n";
        }
        auto add_calls = [&](const std::string& who, const json& of, std::initializer_list<const char*> names) {
            for (const char* name : names) {
                const json d = of.value(name, json::object());
                std::snprintf(line, sizeof line, "| %s | %s | %llu | %.3f | %.3f | %.3f |\n", who.c_str(), name,
                              (unsigned long long)d.value("calls", 0ull), seconds_of(d, "median_seconds"),
                              seconds_of(d, "p99_seconds"), seconds_of(d, "max_seconds"));
                calls_table += line;
            }
        };
        add_calls(backend, calls, {"update_lod", "swap_remove", "add", "step", "frame"});
        for (const json& e : r.value("engine_moving", json::array())) {
            const std::string who = backend + " (" + e.value("path", std::string()) + ")";
            add_calls(who, e.value("calls", json::object()),
                      {"update_lod", "swap_remove", "add", "changes_and_step_call", "frame"});
            std::snprintf(line, sizeof line, "| %s | changes add | | %.3f | | |\n", who.c_str(),
                          e.value("changes_add_seconds", 0.0) * 1e3);
            calls_table += line;
        }
    }
    if (!calls_table.empty())
        out += "\nPer call while moving (ms of wall time; \"(enqueue)\", \"(record)\": the engine's path, after the "
               "standing frames, the frame until its outputs are ready, changes add against its standing frame):\n\n"
               "| backend | call | calls | median | p99 | max |\n"
               "|---|---|--:|--:|--:|--:|\n" + calls_table;
    if (!passes_table.empty())
        out += "\nA standing step: device ms per pass (profiled: the timers serialize the passes), and as an "
               "engine issues it (CUDA: enqueued on its stream; Vulkan: recorded into its command buffer), "
               "ms of the call / of the frame until the outputs are ready:\n\n"
               "| backend | groups | dispatches | passes | engine call / frame |\n|---|--:|--:|---|---|\n" +
               passes_table;
    return out;
}

}  // namespace hmsm::cli::bench
