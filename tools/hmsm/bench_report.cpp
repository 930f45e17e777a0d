// hmsm bench: markdown tables from the JSON document. Missing figures print as "–".
#include "bench_report.h"

#include <hmsm/pass.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <tuple>

namespace hmsm::cli::bench {
namespace {

using nlohmann::json;

const char* kDash = "–";

/// The number at `key` of `j`, if there is one.
bool number_at(const json& j, const char* key, double& out) {
    if (!j.is_object()) return false;
    auto it = j.find(key);
    if (it == j.end() || !it->is_number()) return false;
    out = it->get<double>();
    return true;
}

std::string format(const char* pattern, double value) {
    char text[64];
    std::snprintf(text, sizeof text, pattern, value);
    return text;
}

/// Three significant digits or so, without exponents for the usual ranges.
std::string num(const json& j, const char* key, double scale = 1.0) {
    double v;
    if (!number_at(j, key, v)) return kDash;
    v *= scale;
    const double a = std::fabs(v);
    return format(a >= 1000.0 ? "%.0f" : a >= 100.0 ? "%.1f" : a >= 10.0 ? "%.2f" : a >= 0.01 ? "%.3f" : "%.2e", v);
}

std::string times(const json& j, const char* key) {
    std::string s = num(j, key);
    return s == kDash ? s : s + "×";
}

std::string text(const json& j, const char* key) {
    if (!j.is_object()) return kDash;
    auto it = j.find(key);
    if (it == j.end()) return kDash;
    return it->is_string() ? it->get<std::string>() : it->dump();
}

std::string row(std::initializer_list<std::string> cells) {
    std::string line = "|";
    for (const std::string& c : cells) line += " " + c + " |";
    return line + "\n";
}

const json& member(const json& j, const char* key) {
    static const json null_json;
    if (!j.is_object()) return null_json;
    auto it = j.find(key);
    return it == j.end() ? null_json : *it;
}

/// The vertex layout of a forest entry; documents from before the layouts had only separate.
std::string layout_of(const json& entry) {
    return entry.contains("layout") ? text(entry, "layout") : "separate";
}

/// The layout column of a forest row, with the composition where it is not pointer jumping.
std::string forest_layout_cell(const json& entry) {
    const std::string composition = entry.contains("composition") ? text(entry, "composition") : "pointer_jumping";
    return composition == "pointer_jumping" ? layout_of(entry) : layout_of(entry) + " (" + composition + ")";
}

std::string case_mark(const json& entry) {
    auto it = entry.find("budget_reduced");
    return it != entry.end() && it->is_boolean() && it->get<bool>() ? "*" : "";
}

}  // namespace

std::string render_markdown(const json& d) {
    std::string out;
    const json& settings = member(d, "settings");
    out += "## hmsm bench, " + text(d, "date") + ", commit " + text(d, "commit") +
           (member(d, "quick").is_boolean() && d["quick"].get<bool>() ? " (--quick)" : "") + "\n\n";
    out += "Host: " + text(member(d, "host"), "cpu") + ", " + text(member(d, "host"), "hardware_threads") +
           " hardware threads.";
    for (const json& b : member(d, "backends")) {
        if (member(b, "available").is_boolean() && b["available"].get<bool>())
            out += " `" + text(b, "backend") + "`: " + text(b, "device") + ".";
    }
    out += "\nMedians of " + text(settings, "repeats") + " batches of " + text(settings, "steps_per_batch") +
           " steps after " + text(settings, "warmup_steps") + " warm-up steps; a case marked * " +
           "ran fewer to fit the " + text(settings, "case_budget_seconds") + " s budget per case.\n\n";

    const json& presets = member(d, "presets");
    if (!presets.empty()) {
        out += "### Steps per second, all seven passes (the paper's Table 1)\n\n";
        out += "Pointer jumping, the paper's composition, on every backend (the path walk, the default on "
               "a GPU, is in the composition table below). step(1)/s: one step per call, outputs left on "
               "the device; batched/s: `--steps` steps per call; +readback/s: one step and all vertex positions read to the host "
               "per call (the paper's setting). Speed-ups from the same run over `cpu` (serial "
               "float, the paper's baseline) and over the best CPU backend of the host for that "
               "figure (named in brackets).\n\n";
        out += row({"preset", "vertices", "backend", "step(1)/s", "batched/s", "+readback/s",
                    "× cpu step(1)", "× cpu batched", "× cpu readback", "× best CPU step(1)",
                    "× best CPU batched", "× best CPU readback"});
        out += "|---|--:|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|\n";
        for (const json& p : presets) {
            const json& rate = member(p, "steps_per_second");
            const json& up = member(p, "speedup_over_cpu");
            const json& best_up = member(p, "speedup_over_best_cpu");
            const json& best = member(p, "best_cpu");
            auto over_best = [&](const char* key) {
                const std::string x = times(best_up, key);
                return x == kDash ? x : x + " (" + text(best, key) + ")";
            };
            out += row({text(p, "preset"), text(p, "mesh_vertices"), text(p, "backend") + case_mark(p),
                        num(rate, "per_call"), num(rate, "batched"), num(rate, "readback"),
                        times(up, "per_call"), times(up, "batched"), times(up, "readback"),
                        over_best("per_call"), over_best("batched"), over_best("readback")});
        }

        out += "\n### Device time per pass (µs per step, pointer jumping)\n\n";
        out += "GB/s: the bytes the seven passes must move (docs/benchmarks/README.md) over the "
               "device time of all passes. Steps/s with device timers off and on (batched) show "
               "what the timers themselves cost.\n\n";
        std::string header = "| preset | backend |";
        std::string rule = "|---|---|";
        for (Pass pass : kAllPasses) {
            header.append(" ").append(pass_name(pass)).append(" |");
            rule += "--:|";
        }
        out += header + " total | MB/step | GB/s | steps/s timers off | steps/s timers on |\n" + rule +
               "--:|--:|--:|--:|--:|\n";
        for (const json& p : presets) {
            const json& pj = member(p, "pointer_jumping");
            const json& seconds = member(pj, "pass_seconds_per_step");
            std::string line = "| " + text(p, "preset") + " | " + text(p, "backend") + " |";
            for (Pass pass : kAllPasses)
                line.append(" ").append(num(seconds, std::string(pass_name(pass)).c_str(), 1e6)).append(" |");
            line.append(" ").append(num(pj, "device_seconds_per_step", 1e6));
            line.append(" | ").append(num(member(p, "bytes_per_step"), "total", 1e-6));
            line.append(" | ").append(num(pj, "device_effective_bandwidth", 1e-9));
            line.append(" | ").append(num(pj, "steps_per_second_batched"));
            line.append(" | ").append(num(pj, "steps_per_second_profiled")).append(" |\n");
            out += line;
        }

        out += "\n### Passes 3 and 5: pointer jumping vs all rounds in one dispatch vs level by level vs "
               "path walk\n\n";
        out += "µs per step with device timers on; batched/s with them off. W is the default on a GPU "
               "(Composition::automatic), PJ on the CPU. PJ: Composition::pointer_jumping (one dispatch "
               "per round, or all rounds in one dispatch for models "
               "of at most 512 chains, 1,024 on Vulkan; docs/architecture.md); PJ/1: every round in "
               "one dispatch per pass, a workgroup per instance; LbL: one dispatch per depth level; "
               "W: path walk, passes 3 and 5 in one dispatch in which every chain walks its ancestors from the trunk "
               "down (wind_force with integrate and node_relative with node_world in one dispatch each "
               "too: four dispatches per step).\n\n";
        out += row({"preset", "backend", "rounds / levels", "compose PJ", "compose PJ/1", "compose LbL",
                    "root_positions PJ", "root_positions PJ/1", "root_positions LbL",
                    "compose+root_positions W", "all passes PJ", "all passes PJ/1", "all passes LbL",
                    "all passes W", "batched/s PJ", "batched/s PJ/1", "batched/s LbL", "batched/s W"});
        out += "|---|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:\n";
        for (const json& p : presets) {
            const json& pj = member(p, "pointer_jumping");
            const json& in_dispatch = member(p, "pointer_jumping_in_dispatch");
            const json& lbl = member(p, "level_by_level");
            const json& ps = member(pj, "pass_seconds_per_step");
            const json& rs = member(in_dispatch, "pass_seconds_per_step");
            const json& ls = member(lbl, "pass_seconds_per_step");
            const json& walk = member(p, "path_walk");
            const json& ws = member(walk, "pass_seconds_per_step");
            out += row({text(p, "preset"), text(p, "backend"), text(pj, "rounds") + " / " + text(lbl, "levels"),
                        num(ps, "compose", 1e6), num(rs, "compose", 1e6), num(ls, "compose", 1e6),
                        num(ps, "root_positions", 1e6), num(rs, "root_positions", 1e6),
                        num(ls, "root_positions", 1e6), num(ws, "compose+root_positions", 1e6),
                        num(pj, "device_seconds_per_step", 1e6), num(in_dispatch, "device_seconds_per_step", 1e6),
                        num(lbl, "device_seconds_per_step", 1e6),
                        num(walk, "device_seconds_per_step", 1e6), num(pj, "steps_per_second_batched"),
                        num(in_dispatch, "steps_per_second_batched"), num(lbl, "steps_per_second_batched"),
                        num(walk, "steps_per_second_batched")});
        }
    }

    const json& forest = member(d, "forest");
    const json& skipped = member(d, "skipped");
    bool any_forest_skip = false;
    for (const json& s : skipped) any_forest_skip |= text(s, "section") == "forest";
    if (!forest.empty() || any_forest_skip) {
        out += "\n### Forest scaling: instances of " + text(settings, "forest_model") + "\n\n";
        out += "Batched steps, outputs on the device. GB/s: bytes per step (state + static, "
               "docs/benchmarks/README.md) over wall time per step, and over device time; "
               "% of copy: wall GB/s against the copy bandwidth below. layout: the vertex layout "
               "the contour pass writes (separate: 32 bytes per vertex, packed: 16). × cpu, × best CPU: "
               "steps/s over those of `cpu` and of the fastest CPU backend (in brackets) for the "
               "same instances and layout.\n\n";
        out += row({"backend", "instances", "layout", "vertices", "ms/step", "steps/s", "Mvertices/s", "MB/step",
                    "GB/s wall", "GB/s device", "% of copy", "× cpu", "× best CPU"});
        out += "|---|--:|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|\n";
        // Sorted by backend, instances, then separate before packed (side by side).
        using RowKey = std::tuple<std::string, double, bool>;
        std::map<RowKey, std::string> rows;
        for (const json& f : forest) {
            double n = 0.0;
            number_at(f, "instances", n);
            rows[{text(f, "backend"), n, layout_of(f) == "packed"}] =
                row({text(f, "backend") + case_mark(f), text(f, "instances"), forest_layout_cell(f), text(f, "mesh_vertices"),
                     num(f, "seconds_per_step", 1e3), num(f, "steps_per_second"),
                     num(f, "vertices_per_second", 1e-6), num(f, "bytes_per_step", 1e-6),
                     num(f, "effective_bandwidth", 1e-9), num(f, "device_effective_bandwidth", 1e-9),
                     num(f, "copy_bandwidth_fraction", 100.0), times(f, "speedup_over_cpu"),
                     times(f, "speedup_over_best_cpu") +
                         (f.contains("best_cpu") ? " (" + text(f, "best_cpu") + ")" : "")});
        }
        for (const json& s : skipped) {
            if (text(s, "section") != "forest") continue;
            double n = 0.0;
            number_at(s, "instances", n);
            rows[{text(s, "backend"), n, layout_of(s) == "packed"}] =
                "| " + text(s, "backend") + " | " + text(s, "instances") + " | " + layout_of(s) +
                " | skipped: " + text(s, "reason") + " |||||||||\n";
        }
        for (const auto& [key, line] : rows) out += line;
    }

    const json& copy = member(d, "copy_bandwidth");
    if (!copy.empty()) {
        out += "\n### Copy bandwidth (the roofline), measured in the same run\n\n";
        out += row({"backend", "device", "GB/s", "method", "block MiB"});
        out += "|---|---|--:|---|--:|\n";
        for (const json& c : copy)
            out += row({text(c, "backend"), text(c, "device"), num(c, "bytes_per_second", 1e-9),
                        text(c, "method"), num(c, "bytes", 1.0 / 1048576.0)});
    }

    bool other_skips = false;
    for (const json& s : skipped) other_skips |= text(s, "section") != "forest";
    if (other_skips) {
        out += "\n### Skipped\n\n";
        for (const json& s : skipped) {
            if (text(s, "section") == "forest") continue;
            std::string what = text(s, "backend");
            if (s.contains("preset")) what = text(s, "preset") + " on " + what;
            if (s.contains("composition")) what += " (" + text(s, "composition") + ")";
            out += "- " + what + ": " + text(s, "reason") + "\n";
        }
    }
    const json& notes = member(d, "notes");
    if (!notes.empty()) {
        out += "\n### Notes\n\n";
        for (const json& n : notes) out += "- " + (n.is_string() ? n.get<std::string>() : n.dump()) + "\n";
    }
    return out;
}

}  // namespace hmsm::cli::bench
