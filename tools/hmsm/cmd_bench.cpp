// hmsm bench (docs/model.md 7): the paper's Table 1 per preset and backend, pointer jumping
// vs level by level, and forest scaling against the copy-bandwidth roofline. Markdown on stdout,
// JSON with --json (schema: docs/benchmarks/README.md).
#include "simulation_access.h"
#include "bench_measure.h"
#include "bench_model.h"
#include "bench_report.h"
#include "bench_live.h"
#include "cli_common.h"

#include "scene_data.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <thread>
#include <tuple>

namespace hmsm::cli {
namespace {

using nlohmann::json;
using namespace bench;

constexpr double kMiB = 1048576.0;

struct BenchFlags {
    std::string presets = "paper-1,paper-2,paper-3,paper-4,paper-5";
    std::string tree;
    std::string backends = "cpu,vulkan,cuda";
    int64_t steps = 100, warmup = 20, repeats = 5;
    std::string instances = "1,10,100,1000,10000";
    double spacing = 25.0;
    double case_budget = 20.0;
    bool quick = false, no_progress = false;
    std::string json_path, commit = "unknown", render;
} flags;

std::vector<std::string> split_list(const std::string& text) {
    std::vector<std::string> items;
    std::stringstream in(text);
    std::string item;
    while (std::getline(in, item, ',')) {
        const size_t a = item.find_first_not_of(" \t"), b = item.find_last_not_of(" \t");
        items.push_back(a == std::string::npos ? "" : item.substr(a, b - a + 1));
    }
    return items;
}

std::string utc_now() {
    std::time_t now = std::time(nullptr);
    std::tm tm{};
    gmtime_r(&now, &tm);
    char text[32];
    std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &tm);
    return text;
}

std::string format_seconds(double s) {
    char text[32];
    std::snprintf(text, sizeof text, s >= 10 ? "%.0f s" : s >= 0.01 ? "%.2f s" : "%.2e s", s);
    return text;
}

struct Model {
    std::string name;
    TreeModel tree;
};

struct BackendRun {
    BackendKind kind;
    bool available = true;
    std::string device;
    std::optional<CopyBandwidth> copy;
};

bool is_host_kind(BackendKind k) { return k == BackendKind::cpu || k == BackendKind::cpu64; }

/// Backends whose "device" memory is host memory: the CPU ones and Vulkan CPU drivers.
bool uses_host_memory(const BackendRun& b) {
    if (is_host_kind(b.kind)) return true;
    for (const char* cpu_driver : {"llvmpipe", "lavapipe", "SwiftShader"})
        if (b.device.find(cpu_driver) != std::string::npos) return true;
    return false;
}

/// Statuses that mean "this case does not fit here", reported as skips rather than failures.
bool is_skip(const Status& s) {
    return s.code() == ErrorCode::out_of_memory || s.code() == ErrorCode::unsupported;
}

json pass_seconds_json(const CaseResult& r) {
    json seconds = json::object();
    for (Pass p : kAllPasses) seconds[std::string(pass_name(p))] = r.pass_seconds[uint32_t(p)];
    return seconds;
}

/// Keeps only positive, finite figures (the schema's promise).
void put(json& j, const char* key, double value) {
    if (std::isfinite(value) && value > 0.0) j[key] = value;
}

constexpr std::array<VertexLayout, 2> kVertexLayouts = {VertexLayout::separate, VertexLayout::packed};

class BenchRun {
public:
    BenchRun(const Settings& settings, uint64_t device_copy_bytes, uint64_t host_copy_bytes,
             Progress& progress)
        : settings_(settings), device_copy_bytes_(device_copy_bytes),
          host_copy_bytes_(host_copy_bytes), progress_(progress) {}

    std::vector<BackendRun> backends;
    json presets = json::array(), forest = json::array(), skipped = json::array();
    int failures = 0;

    /// Creates a simulation; on failure records why (a skip, an unavailable backend or a
    /// failure) under `where` and returns null.
    std::unique_ptr<Simulation> create(const Scene& scene, BackendRun& b, Composition composition,
                                       json where, VertexLayout layout = VertexLayout::separate) {
        SimulationConfig config;
        config.backend = b.kind;
        config.composition = composition;
        config.vertex_layout = layout;
        config.profile_passes = false;
        auto sim = Simulation::create(scene, config);
        if (sim) {
            b.device = (*sim)->device_name();
            return std::move(sim).value();
        }
        const Status& s = sim.status();
        if (s.code() == ErrorCode::no_device) {
            b.available = false;
            skipped.push_back({{"section", "backend"}, {"backend", to_string(b.kind)},
                               {"reason", "not available: " + s.message()}});
            progress_.note(std::string(to_string(b.kind)) + " not available: " + s.message());
            return nullptr;
        }
        record_failure(where, s);
        return nullptr;
    }

    void record_failure(json where, const Status& s) {
        const bool skip = is_skip(s);
        where["reason"] = (skip ? "" : "failed: ") + s.message();
        if (!skip) ++failures;
        progress_.note((skip ? "skipped " : "FAILED ") + where.dump() );
        skipped.push_back(std::move(where));
    }

    void copy_bandwidth(BackendRun& b, Simulation& sim) {
        if (b.copy && b.copy->method != "host_transfer_estimate") return;
        if (b.copy && double(sim.vertex_count()) * 16.0 <= double(b.copy->bytes)) return;
        if (b.copy && double(sim.vertex_count()) * 16.0 > 2048.0 * kMiB) return;
        // A CPU Vulkan driver's device memory is host memory: its roofline is the host memcpy.
        // Measured once and shared, so host-memory backends are compared against the same figure.
        if (uses_host_memory(b) && !host_copy_) {
            Result<CopyBandwidth> host = host_memcpy_bandwidth(host_copy_bytes_, 5);
            if (host) host_copy_ = *host;
        }
        Result<CopyBandwidth> bw = uses_host_memory(b)
                                       ? (host_copy_ ? Result<CopyBandwidth>(*host_copy_)
                                                     : Status{ErrorCode::out_of_memory, "host memcpy failed"})
                                       : device_copy_bandwidth(sim, device_copy_bytes_);
        if (bw) b.copy = *bw;
        else progress_.note(std::string(to_string(b.kind)) + ": copy bandwidth: " + bw.status().message());
    }

    void preset_case(const Model& m, BackendRun& b) {
        const std::string backend = to_string(b.kind);
        const Scene scene = single_tree_scene(m.tree);
        json entry = {{"preset", m.name}, {"backend", backend}, {"instances", 1}};

        progress_.begin(m.name + " on " + backend + ", pointer jumping");
        auto sim = create(scene, b, Composition::pointer_jumping,
                          {{"section", "presets"}, {"preset", m.name}, {"backend", backend},
                           {"composition", "pointer_jumping"}});
        if (!sim) return;
        auto measured = measure(*sim, settings_, kBatched | kPerCall | kReadback | kPasses);
        if (!measured) return record_failure({{"section", "presets"}, {"preset", m.name}, {"backend", backend},
                                              {"composition", "pointer_jumping"}}, measured.status());
        const CaseResult& r = *measured;
        const Traffic traffic = step_traffic(*sim);
        entry["device"] = sim->device_name();
        entry["nodes"] = sim->node_count();
        entry["chains"] = sim->chain_count();
        entry["mesh_vertices"] = sim->vertex_count();
        entry["steps_per_batch"] = r.steps;
        entry["repeats"] = r.repeats;
        entry["budget_reduced"] = r.reduced;
        json rate = json::object();
        put(rate, "per_call", r.per_call);
        put(rate, "batched", r.batched);
        put(rate, "readback", r.readback);
        entry["steps_per_second"] = rate;
        json bytes = {{"state", traffic.state_bytes}, {"static", traffic.static_bytes}, {"total", traffic.total()}};
        json per_pass = json::object();
        for (Pass p : kAllPasses) per_pass[std::string(pass_name(p))] = traffic.pass_bytes[uint32_t(p)];
        bytes["per_pass"] = per_pass;
        entry["bytes_per_step"] = bytes;
        put(entry, "effective_bandwidth", traffic.total() * r.batched);
        json pj = {{"rounds", sim->jump_rounds()}};
        put(pj, "steps_per_second_batched", r.batched);
        put(pj, "steps_per_second_profiled", r.profiled);
        if (r.has_passes) {
            pj["pass_seconds_per_step"] = pass_seconds_json(r);
            put(pj, "device_seconds_per_step", r.device_seconds);
            put(pj, "device_effective_bandwidth", traffic.total() / r.device_seconds);
        }
        entry["pointer_jumping"] = pj;
        const uint32_t levels = uint32_t(hmsm::detail::scene_data_of(*sim).models[0].level_begin.size() - 1);
        const uint32_t rounds = sim->jump_rounds();
        copy_bandwidth(b, *sim);
        sim.reset();

        for (auto [composition, count_key, count] :
             {std::tuple{Composition::pointer_jumping_in_dispatch, "rounds", rounds},
              std::tuple{Composition::level_by_level, "levels", levels}}) {
            const std::string name = to_string(composition);
            progress_.begin(m.name + " on " + backend + ", " + name);
            json where = {{"section", "presets"}, {"preset", m.name}, {"backend", backend}, {"composition", name}};
            auto other = create(scene, b, composition, where);
            if (!other) continue;
            auto measured_other = measure(*other, settings_, kBatched | kPasses);
            if (!measured_other) {
                record_failure(where, measured_other.status());
                continue;
            }
            json c = {{count_key, count}};
            put(c, "steps_per_second_batched", measured_other->batched);
            put(c, "steps_per_second_profiled", measured_other->profiled);
            if (measured_other->has_passes) {
                c["pass_seconds_per_step"] = pass_seconds_json(*measured_other);
                put(c, "device_seconds_per_step", measured_other->device_seconds);
                put(c, "device_effective_bandwidth", traffic.total() / measured_other->device_seconds);
            }
            entry[name] = c;
            entry["budget_reduced"] = entry["budget_reduced"].get<bool>() || measured_other->reduced;
        }
        presets.push_back(entry);
    }

    /// Each forest size in both vertex layouts, side by side: the contour pass writes 32 bytes
    /// per vertex in the separate layout and 16 in the packed one.
    void forest_cases(const Model& model, BackendRun& b, const std::vector<uint32_t>& counts,
                      double spacing, double state_per_instance) {
        const std::string backend = to_string(b.kind);
        double last_per_step = 0.0;
        uint32_t last_count = 0;
        for (uint32_t n : counts) {
            if (!b.available) return;
            auto skip_size = [&](const std::string& reason) {
                for (VertexLayout layout : kVertexLayouts)
                    skipped.push_back({{"section", "forest"}, {"backend", backend}, {"instances", n},
                                       {"layout", to_string(layout)}, {"reason", reason}});
                progress_.note("skipped " + std::to_string(n) + " x " + model.name + " on " + backend + ": " + reason);
            };
            const double available = host_available_memory();
            const double needed = state_per_instance * n * (is_host_kind(b.kind) ? 1.0 : 2.0);
            if (uses_host_memory(b) && available > 0.0 && needed > 0.8 * available) {
                char reason[160];
                std::snprintf(reason, sizeof reason, "needs about %.1f GB of host memory, %.1f GB available",
                              needed * 1e-9, available * 1e-9);
                skip_size(reason);
                continue;
            }
            if (last_count > 0) {
                // Linear extrapolation from the slowest layout of the last size; the least a
                // case runs is 1 warm-up + 3 x (batched + timed), once per layout.
                const double estimate = last_per_step * double(n) / double(last_count);
                if (estimate * 7.0 * double(kVertexLayouts.size()) > settings_.case_budget) {
                    skip_size("about " + format_seconds(estimate) + " per step (extrapolated from " +
                              std::to_string(last_count) + " instances), over the " +
                              format_seconds(settings_.case_budget) + " case budget (--case-budget)");
                    continue;
                }
            }
            auto scene = grid_scene(model.tree, n, spacing, 1);
            double slowest = 0.0;
            for (VertexLayout layout : kVertexLayouts) {
                if (!b.available) return;
                const std::string layout_name = to_string(layout);
                progress_.begin(std::to_string(n) + " x " + model.name + " on " + backend + ", " + layout_name);
                json where = {{"section", "forest"}, {"backend", backend}, {"instances", n}, {"layout", layout_name}};
                if (!scene) {
                    record_failure(where, scene.status());
                    continue;
                }
                auto sim = create(*scene, b, Composition::pointer_jumping, where, layout);
                if (!sim) continue;
                auto measured = measure(*sim, settings_, kBatched | kPasses);
                if (!measured) {
                    record_failure(where, measured.status());
                    continue;
                }
                const CaseResult& r = *measured;
                slowest = std::max(slowest, r.warmup_seconds_per_step);
                const Traffic traffic = step_traffic(*sim);
                json f = {{"backend", backend}, {"device", sim->device_name()}, {"instances", n},
                          {"layout", layout_name}, {"mesh_vertices", sim->vertex_count()},
                          {"steps_per_batch", r.steps}, {"repeats", r.repeats}, {"budget_reduced", r.reduced},
                          {"bytes_per_step", traffic.total()}, {"state_bytes_per_step", traffic.state_bytes}};
                put(f, "steps_per_second", r.batched);
                put(f, "seconds_per_step", 1.0 / r.batched);
                put(f, "vertices_per_second", double(sim->vertex_count()) * r.batched);
                put(f, "effective_bandwidth", traffic.total() * r.batched);
                put(f, "steps_per_second_profiled", r.profiled);
                if (r.has_passes) {
                    put(f, "device_seconds_per_step", r.device_seconds);
                    put(f, "device_effective_bandwidth", traffic.total() / r.device_seconds);
                }
                copy_bandwidth(b, *sim);
                forest.push_back(f);
            }
            if (slowest > 0.0) {
                last_per_step = slowest;
                last_count = n;
            }
        }
    }

private:
    Settings settings_;
    uint64_t device_copy_bytes_, host_copy_bytes_;
    std::optional<CopyBandwidth> host_copy_;
    Progress& progress_;
};

int render(const std::string& path) {
    std::ifstream in(path);
    if (!in) return fail_input("--render '" + path + "': cannot read the file");
    json document = json::parse(in, nullptr, false);
    if (document.is_discarded() || !document.is_object() || document.value("format", "") != "hmsm-bench")
        return fail_input("--render '" + path + "': not an hmsm-bench JSON document");
    std::fputs(render_markdown(document).c_str(), stdout);
    return kExitOk;
}

}  // namespace

void register_bench_flags(CLI::App& app) {
    app.add_option("--presets", flags.presets, "comma-separated presets (default paper-1,...,paper-5; none: forest only)");
    app.add_option("--tree", flags.tree, "benchmark this hmsm-tree file instead of the presets "
                                         "(also the forest model)");
    app.add_option("--backends", flags.backends, "comma-separated backends (default cpu,vulkan,cuda; "
                                                 "unavailable ones are skipped with a note)");
    app.add_option("--steps", flags.steps, "steps per timed batch (default 100)");
    app.add_option("--warmup", flags.warmup, "warm-up steps before timing (default 20)");
    app.add_option("--repeats", flags.repeats, "timed batches per figure; medians are reported (default 5)");
    app.add_option("--instances", flags.instances,
                   "forest sizes of paper-1, comma-separated (default 1,10,100,1000,10000; none: no forest)");
    app.add_option("--spacing", flags.spacing, "forest grid spacing in metres (default 25)");
    app.add_option("--case-budget", flags.case_budget,
                   "seconds one case may take: slower cases run fewer steps, forest sizes "
                   "extrapolated past it are skipped (default 20)");
    app.add_flag("--quick", flags.quick, "CI-sized run: paper-5, 5 steps, instances 1,10 (explicit flags win)");
    app.add_option("--json", flags.json_path, "write the results as JSON (docs/benchmarks/README.md)");
    app.add_option("--commit", flags.commit, "commit id to record in the results");
    app.add_flag("--no-progress", flags.no_progress, "no progress on stderr");
    app.add_option("--render", flags.render, "print the markdown tables of an earlier --json file and exit");
}

int run_bench(CLI::App& app) {
    if (!flags.render.empty()) return render(flags.render);
    if (flags.quick) {
        if (!app.count("--presets") && flags.tree.empty()) flags.presets = "paper-5";
        if (!app.count("--steps")) flags.steps = 5;
        if (!app.count("--warmup")) flags.warmup = 2;
        if (!app.count("--repeats")) flags.repeats = 3;
        if (!app.count("--instances")) flags.instances = "1,10";
        if (!app.count("--case-budget")) flags.case_budget = 5.0;
    }
    if (flags.steps < 1 || flags.steps > 1000000)
        return fail_input("--steps " + std::to_string(flags.steps) + ": must be in [1, 1000000]");
    if (flags.warmup < 0 || flags.warmup > 1000000)
        return fail_input("--warmup " + std::to_string(flags.warmup) + ": must be in [0, 1000000]");
    if (flags.repeats < 1 || flags.repeats > 1000)
        return fail_input("--repeats " + std::to_string(flags.repeats) + ": must be in [1, 1000]");
    if (!(flags.case_budget > 0.0) || !std::isfinite(flags.case_budget))
        return fail_input("--case-budget: must be a positive number of seconds");
    if (!(flags.spacing >= 0.0) || !std::isfinite(flags.spacing))
        return fail_input("--spacing: must be a finite number >= 0");

    // Backends: every one named must be known; ones not compiled in are skipped with a note.
    std::vector<BackendRun> backends;
    json skipped_backends = json::array();
    const auto compiled = compiled_backends();
    for (const std::string& name : split_list(flags.backends)) {
        auto kind = parse_backend_kind(name);
        if (!kind || *kind == BackendKind::automatic)
            return fail_input("--backends '" + name + "': expected cpu, cpu64, vulkan or cuda");
        bool duplicate = false;
        for (const auto& b : backends) duplicate |= b.kind == *kind;
        if (duplicate) continue;
        if (std::find(compiled.begin(), compiled.end(), *kind) == compiled.end()) {
            skipped_backends.push_back({{"section", "backend"}, {"backend", name},
                                        {"reason", "not compiled into this build"}});
            continue;
        }
        backends.push_back(BackendRun{*kind, true, {}, std::nullopt});
    }

    std::vector<uint32_t> counts;
    if (flags.instances != "none") {
        for (const std::string& item : split_list(flags.instances)) {
            char* end = nullptr;
            const long long n = std::strtoll(item.c_str(), &end, 10);
            if (item.empty() || *end != '\0' || n < 1 || n > 1000000)
                return fail_input("--instances '" + item + "': expected counts in [1, 1000000] or none");
            counts.push_back(uint32_t(n));
        }
    }

    // Models: the presets (or --tree), and the forest model (paper-1 or --tree).
    std::vector<Model> models;
    Model forest_model;
    if (!flags.tree.empty()) {
        auto tree = load_tree(flags.tree);
        if (!tree) return fail(tree.status());
        forest_model = {std::filesystem::path(flags.tree).stem().string(), *tree};
        models.push_back(forest_model);
    } else {
        for (const std::string& name : split_list(flags.presets == "none" ? "" : flags.presets)) {
            auto tree = generate_preset(name);
            if (!tree) return fail(Status{tree.status().code(), "--presets: " + tree.status().message()});
            models.push_back({name, std::move(tree).value()});
        }
        if (!counts.empty()) {
            auto tree = generate_preset("paper-1");
            if (!tree) return fail(tree.status());
            forest_model = {"paper-1", std::move(tree).value()};
        }
    }

    StagedOutputs outputs;
    std::optional<size_t> json_file;
    if (!flags.json_path.empty()) {
        auto staged = outputs.stage(flags.json_path, "--json");
        if (!staged) return fail(staged.status());
        json_file = *staged;
    }

    Settings settings{uint32_t(flags.steps), uint32_t(flags.warmup), uint32_t(flags.repeats), flags.case_budget};
    const uint64_t device_copy_bytes = uint64_t((flags.quick ? 64.0 : 1024.0) * kMiB);
    const uint64_t host_copy_bytes = uint64_t((flags.quick ? 32.0 : 256.0) * kMiB);
    Progress progress(backends.size() * (2 * models.size() + counts.size()), !flags.no_progress);
    BenchRun run(settings, device_copy_bytes, host_copy_bytes, progress);
    run.backends = backends;
    for (const json& s : skipped_backends) {
        run.skipped.push_back(s);
        progress.note(s["backend"].get<std::string>() + " skipped: not compiled into this build");
    }

    for (const Model& m : models)
        for (BackendRun& b : run.backends)
            if (b.available) run.preset_case(m, b);

    if (!counts.empty()) {
        // State bytes per instance, for the host-memory check of CPU-memory backends.
        SimulationConfig probe_config;
        probe_config.backend = BackendKind::cpu;
        probe_config.profile_passes = false;
        auto probe = Simulation::create(single_tree_scene(forest_model.tree), probe_config);
        if (!probe) return fail(probe.status());
        const double state_per_instance = state_bytes_per_instance(**probe);
        probe->reset();
        for (BackendRun& b : run.backends)
            if (b.available) run.forest_cases(forest_model, b, counts, flags.spacing, state_per_instance);
    }
    std::vector<BackendKind> live_backends;
    for (const BackendRun& b : run.backends)
        if (b.available) live_backends.push_back(b.kind);
    const json live_control = counts.empty() ? json::array()
                                             : measure_live_control(forest_model.tree, live_backends,
                                                                    flags.quick ? 20u : 1000u, flags.spacing);
    progress.finish();

    // Speed-ups over cpu, preset by preset, from this run.
    std::map<std::string, json> cpu_rates;
    for (const json& p : run.presets)
        if (p["backend"] == "cpu") cpu_rates[p["preset"].get<std::string>()] = p["steps_per_second"];
    for (json& p : run.presets) {
        auto cpu = cpu_rates.find(p["preset"].get<std::string>());
        if (cpu == cpu_rates.end()) continue;
        json up = json::object();
        for (const char* key : {"per_call", "batched", "readback"})
            if (p["steps_per_second"].contains(key) && cpu->second.contains(key))
                put(up, key, p["steps_per_second"][key].get<double>() / cpu->second[key].get<double>());
        p["speedup_over_cpu"] = up;
    }

    json copy = json::array();
    std::map<std::string, double> copy_by_backend;
    bool estimated_copy = false;
    for (const BackendRun& b : run.backends) {
        if (!b.copy) continue;
        copy.push_back({{"backend", to_string(b.kind)}, {"device", b.device},
                        {"bytes_per_second", b.copy->bytes_per_second}, {"method", b.copy->method},
                        {"bytes", b.copy->bytes}});
        copy_by_backend[to_string(b.kind)] = b.copy->bytes_per_second;
        estimated_copy |= b.copy->method == "host_transfer_estimate";
    }
    for (json& f : run.forest) {
        auto bw = copy_by_backend.find(f["backend"].get<std::string>());
        if (bw == copy_by_backend.end()) continue;
        if (f.contains("effective_bandwidth"))
            put(f, "copy_bandwidth_fraction", f["effective_bandwidth"].get<double>() / bw->second);
        if (f.contains("device_effective_bandwidth"))
            put(f, "device_copy_bandwidth_fraction", f["device_effective_bandwidth"].get<double>() / bw->second);
    }

    json backends_json = json::array();
    for (const BackendRun& b : run.backends) {
        json entry = {{"backend", to_string(b.kind)}, {"available", b.available}};
        if (!b.device.empty()) entry["device"] = b.device;
        backends_json.push_back(entry);
    }
    json notes = json::array();
    notes.push_back("cpu is the serial float reference on one thread (the paper's baseline): its pass "
                    "times are host clocks and its forest sizes stop where the extrapolated time per "
                    "case passes --case-budget.");
    notes.push_back("Bytes per step count what the seven passes must move (each buffer a pass "
                    "touches, once); see docs/benchmarks/README.md.");
    if (estimated_copy)
        notes.push_back("A copy bandwidth measured as host_transfer_estimate is the host <-> device "
                        "transfer rate (that backend has no device copy yet): its % of copy is not a "
                        "device-memory roofline.");

    json document = {
        {"format", "hmsm-bench"},
        {"version", 1},
        {"date", utc_now()},
        {"commit", flags.commit},
        {"quick", flags.quick},
        {"host", {{"cpu", host_cpu_name()}, {"hardware_threads", std::max(1u, std::thread::hardware_concurrency())}}},
        {"settings", {{"steps_per_batch", settings.steps}, {"warmup_steps", settings.warmup},
                      {"repeats", settings.repeats}, {"case_budget_seconds", settings.case_budget},
                      {"instances", counts}, {"forest_model", forest_model.name}, {"spacing", flags.spacing},
                      {"forest_layouts", {to_string(kVertexLayouts[0]), to_string(kVertexLayouts[1])}}}},
        {"backends", backends_json},
        {"presets", run.presets},
        {"forest", run.forest},
        {"live_control", live_control},
        {"copy_bandwidth", copy},
        {"skipped", run.skipped},
        {"notes", notes},
    };
    if (counts.empty()) {
        document["settings"].erase("forest_model");
        document["settings"].erase("forest_layouts");
    }

    std::fputs(render_markdown(document).c_str(), stdout);
    std::fflush(stdout);
    if (json_file) {
        std::string text = document.dump(2) + "\n";
        Status written = outputs.write(*json_file, text.data(), text.size());
        if (!written) return fail(written);
    }
    Status committed = outputs.commit();
    if (!committed) return fail(committed);
    if (run.failures > 0) {
        std::fprintf(stderr, "hmsm: error: %d benchmark case(s) failed (see \"skipped\")\n", run.failures);
        return kExitInternal;
    }
    return kExitOk;
}

}  // namespace hmsm::cli
