// hmsm bench (docs/model.md 7): the paper's Table 1 per preset and backend, pointer jumping
// vs level by level, and forest scaling against the copy-bandwidth roofline. Markdown on stdout,
// JSON with --json (schema: docs/benchmarks/README.md).
#include "bench_joints.h"
#include "bench_report.h"
#include "bench_run.h"
#include "bench_live.h"
#include "cli_common.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <thread>

namespace hmsm::cli {
namespace {

using nlohmann::json;
using namespace bench;

constexpr double kMiB = 1048576.0;

struct BenchFlags {
    std::string presets = "paper-1,paper-2,paper-3,paper-4,paper-5";
    std::string tree;
    std::string backends = "cpu,cpu-parallel,vulkan,cuda";
    int64_t steps = 100, warmup = 20, repeats = 5;
    std::string instances = "1,10,100,1000,10000";
    std::string joint_instances = "1,10,100,1000,10000";  // joints-only forest (bench_joints.h)
    double spacing = 25.0;
    double case_budget = 20.0;
    std::string forest_composition = "automatic";
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

int render(const std::string& path) {
    std::ifstream in(path);
    if (!in) return fail_input("--render '" + path + "': cannot read the file");
    json document = json::parse(in, nullptr, false);
    if (document.is_discarded() || !document.is_object() || document.value("format", "") != "hmsm-bench")
        return fail_input("--render '" + path + "': not an hmsm-bench JSON document");
    std::fputs(render_markdown(document).c_str(), stdout);
    std::fputs(bench::render_joint_forest(document.value("forest_joints", json::array())).c_str(), stdout);
    std::fputs(bench::render_live_control(document.value("live_control", json::array())).c_str(), stdout);
    return kExitOk;
}

}  // namespace

void register_bench_flags(CLI::App& app) {
    app.add_option("--presets", flags.presets, "comma-separated presets (default paper-1,...,paper-5; none: forest only)");
    app.add_option("--tree", flags.tree, "benchmark this hmsm-tree file instead of the presets "
                                         "(also the forest model)");
    app.add_option("--backends", flags.backends, "comma-separated backends (default cpu,cpu-parallel,vulkan,cuda; "
                                                 "unavailable ones are skipped with a note)");
    add_integer_option(app, "--steps", flags.steps, "steps per timed batch (default 100)");
    add_integer_option(app, "--warmup", flags.warmup, "warm-up steps before timing (default 20)");
    add_integer_option(app, "--repeats", flags.repeats, "timed batches per figure; medians are reported (default 5)");
    app.add_option("--instances", flags.instances,
                   "forest sizes of paper-1, comma-separated (default 1,10,100,1000,10000; none: no forest)");
    app.add_option("--joint-instances", flags.joint_instances,
                   "joints-only forest sizes of paper-1 (outputs joints, passes 1-5), comma-separated "
                   "(default 1,10,100,1000,10000, plus 100000 x paper-5 unless --quick; none: no rows)");
    app.add_option("--spacing", flags.spacing, "forest grid spacing in metres (default 25)");
    app.add_option("--forest-composition", flags.forest_composition,
                   "composition of the forest rows (default automatic, the library's default; e.g. pointer_jumping)");
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
        if (!app.count("--joint-instances")) flags.joint_instances = "1,10";
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
    const auto forest_composition = parse_composition(flags.forest_composition);
    if (!forest_composition)
        return fail_input("--forest-composition '" + flags.forest_composition + "': unknown composition");
    if (!(flags.spacing >= 0.0) || !std::isfinite(flags.spacing))
        return fail_input("--spacing: must be a finite number >= 0");

    // Backends: every one named must be known; ones not compiled in are skipped with a note.
    std::vector<BackendRun> backends;
    json skipped_backends = json::array();
    const auto compiled = compiled_backends();
    for (const std::string& name : split_list(flags.backends)) {
        auto kind = parse_backend_kind(name);
        if (!kind || *kind == BackendKind::automatic)
            return fail_input("--backends '" + name + "': expected cpu, cpu-parallel, cpu64, vulkan or cuda");
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

    std::vector<uint32_t> joint_counts;
    if (flags.joint_instances != "none") {
        for (const std::string& item : split_list(flags.joint_instances)) {
            char* end = nullptr;
            const long long n = std::strtoll(item.c_str(), &end, 10);
            if (item.empty() || *end != '\0' || n < 1 || n > 1000000)
                return fail_input("--joint-instances '" + item + "': expected counts in [1, 1000000] or none");
            joint_counts.push_back(uint32_t(n));
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

    Settings settings{uint32_t(flags.steps), uint32_t(flags.warmup), uint32_t(flags.repeats), flags.case_budget,
                      *forest_composition};
    const uint64_t device_copy_bytes = uint64_t((flags.quick ? 64.0 : 1024.0) * kMiB);
    const uint64_t host_copy_bytes = uint64_t((flags.quick ? 32.0 : 256.0) * kMiB);
    // Joints-only forest cases: the forest model (paper-1 or --tree) at each size, and a
    // large forest of a small preset (paper-5) as memory and the case budget allow.
    std::vector<bench::JointForestCase> joint_cases;
    if (!joint_counts.empty()) {
        Model joint_model = forest_model;
        if (joint_model.name.empty()) {
            auto tree = flags.tree.empty() ? generate_preset("paper-1") : load_tree(flags.tree);
            if (!tree) return fail(tree.status());
            joint_model = {flags.tree.empty() ? "paper-1" : std::filesystem::path(flags.tree).stem().string(),
                           std::move(tree).value()};
        }
        for (uint32_t n : joint_counts) joint_cases.push_back({joint_model.name, joint_model.tree, n});
        if (!flags.quick && flags.tree.empty()) {
            auto small = generate_preset("paper-5");
            if (!small) return fail(small.status());
            joint_cases.push_back({"paper-5", std::move(small).value(), 100000});
        }
    }
    Progress progress(backends.size() * (2 * models.size() + counts.size() + joint_cases.size()),
                      !flags.no_progress);
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
    json forest_joints = json::array();
    for (BackendRun& b : run.backends)
        if (b.available && !joint_cases.empty())
            run.failures += bench::joint_forest_cases(b.kind, joint_cases, flags.spacing, settings, progress,
                                                      forest_joints, run.skipped);
    std::vector<BackendKind> live_backends;
    for (const BackendRun& b : run.backends)
        if (b.available) live_backends.push_back(b.kind);
    const json live_control = counts.empty() ? json::array()
                                             : measure_live_control(forest_model.tree, live_backends,
                                                                    flags.quick ? 20u : 1000u, flags.spacing);
    progress.finish();

    add_speedups(run.presets, run.forest);

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
    notes.push_back("cpu-parallel runs the same float passes on every hardware thread of the host "
                    "(HMSM_CPU_THREADS overrides); speed-ups are given over cpu and over the best "
                    "CPU backend (cpu, cpu-parallel, cpu64) of the same case in this run.");
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
                      {"forest_composition", to_string(settings.forest_composition)},
                      {"instances", counts}, {"forest_model", forest_model.name}, {"spacing", flags.spacing},
                      {"forest_layouts", {to_string(kVertexLayouts[0]), to_string(kVertexLayouts[1])}}}},
        {"backends", backends_json},
        {"presets", run.presets},
        {"forest", run.forest},
        {"forest_joints", forest_joints},
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
    std::fputs(bench::render_joint_forest(forest_joints).c_str(), stdout);
    std::fputs(bench::render_live_control(live_control).c_str(), stdout);
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
