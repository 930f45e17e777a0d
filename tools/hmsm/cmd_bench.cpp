// hmsm bench (docs/model.md 7): the paper's Table 1 per preset and backend, pointer jumping
// vs level by level, and forest scaling against the copy-bandwidth roofline. Markdown on stdout,
// JSON with --json (schema: docs/benchmarks/README.md), both as a device's page with --out.
#include "bench_depth.h"
#include "bench_dynamics.h"
#include "bench_frames.h"
#include "bench_joints.h"
#include "bench_live.h"
#include "bench_open_world.h"
#include "bench_page.h"
#include "bench_report.h"
#include "bench_run.h"
#include "cli_common.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <filesystem>
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
    std::string composition_depths = "none";
    int64_t frames = 0, frame_steps = 1;  // frame table (bench_frames.h): frames per change (0: no table), steps per frame
    std::string frame_instances = "1,100,1000,10000";  // path walk against pointer jumping (bench_depth.h)
    double spacing = 25.0;
    double case_budget = 20.0;
    std::string forest_composition = "automatic";
    std::string wind = "y1";
    bool open_world = false;  // the open-world case (bench_open_world.h)
    int64_t open_world_trees = 500000, open_world_frames = 300, open_world_changes = 0;
    int64_t open_world_fade_steps = LodBands{}.fade_steps;
    double open_world_fade_bound = 0.0;  // as an engine sets it for a world in wind (docs/driving.md)
    std::string dynamics = "paper";  // coupled: also the dynamics table (bench_dynamics.h)
    std::string open_world_layout = "placed";  // SimulationConfig::instance_layout of the open world
    bool quick = false, no_progress = false;
    std::string json_path, out_stem, commit = "unknown", render;
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

/// Counts "N,N,..." in [1, `largest`] (`what`: "counts", "depths"), or "none" (no rows).
Result<std::vector<uint32_t>> count_list(const std::string& text, const std::string& flag, long long largest,
                                         const char* what) {
    std::vector<uint32_t> counts;
    if (text == "none") return counts;
    for (const std::string& item : split_list(text)) {
        char* end = nullptr;
        const long long n = std::strtoll(item.c_str(), &end, 10);
        if (item.empty() || *end != '\0' || n < 1 || n > largest)
            return Status{ErrorCode::invalid_argument, flag + " '" + detail::quote_input(item) + "': expected " +
                                                           what + " in [1, " + std::to_string(largest) + "] or none"};
        counts.push_back(uint32_t(n));
    }
    return counts;
}

std::string utc_now() {
    std::time_t now = std::time(nullptr);
    std::tm tm{};
    gmtime_r(&now, &tm);
    char text[32];
    std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &tm);
    return text;
}

}  // namespace

void register_bench_flags(CLI::App& app) {
    app.add_option("--presets", flags.presets, "comma-separated presets (default paper-1,...,paper-5; none: forest only)");
    app.add_option("--tree", flags.tree, "benchmark this hmsm-tree file instead of the presets "
                                         "(also the forest model)");
    app.add_option("--backends", flags.backends,
                   "comma-separated backends: " + backend_choices(std::nullopt, false) +
                       " (default cpu,cpu-parallel,vulkan,cuda; unavailable ones are skipped with a note)");
    add_integer_option(app, "--steps", flags.steps, "steps per timed batch (default 100)");
    add_integer_option(app, "--warmup", flags.warmup, "warm-up steps before timing (default 20)");
    add_integer_option(app, "--repeats", flags.repeats, "timed batches per figure; medians are reported (default 5)");
    app.add_option("--instances", flags.instances,
                   "forest sizes of paper-1, comma-separated (default 1,10,100,1000,10000; none: no forest)");
    app.add_option("--joint-instances", flags.joint_instances,
                   "joints-only forest sizes of paper-1 (outputs joints, passes 1-5), comma-separated "
                   "(default 1,10,100,1000,10000, plus 100000 x paper-5 unless --quick; none: no rows)");
    app.add_option("--composition-depths", flags.composition_depths,
                   "path_walk against pointer_jumping per step on synthetic chains of these depths, "
                   "1 and 100 instances, e.g. 16,32,64,128,256,1024 (default none)");
    add_integer_option(app, "--frames", flags.frames,
                       "also time one step per frame as an engine calls it (frame table): this many frames "
                       "per change, fewer where --case-budget says (default 0: no table)");
    app.add_option("--frame-instances", flags.frame_instances,
                   "joints-only paper-1 forest sizes of the frame table (default 1,100,1000,10000)");
    add_integer_option(app, "--frame-steps", flags.frame_steps, "steps per frame of the frame table (default 1)");
    app.add_option("--spacing", flags.spacing, "forest grid spacing in metres (default 25)");
    app.add_option("--forest-composition", flags.forest_composition,
                   "composition of the forest rows: " +
                       choices(kCompositionNames, Spelling::hyphens, Composition::automatic) +
                       "; automatic is the library's default");
    app.add_option("--wind", flags.wind, "wind profile of every case (default y1; names as for simulate --wind)");
    app.add_option("--dynamics", flags.dynamics,
                   "paper (default) or coupled: coupled adds a table of ms per step under the paper's and the "
                   "coupled dynamics (docs/model.md 3.13) for one paper-1 tree and 10,000 joints-only trees "
                   "(--tree's model if given; 10 trees with --quick) on each backend, with coupled / paper");
    app.add_flag("--open-world", flags.open_world,
                 "also run the open world: paper-1 trees (--tree's model) on an endless grid streamed around "
                 "a moving viewer, levels of detail by distance, one step per frame (docs/benchmarks/README.md)");
    add_integer_option(app, "--open-world-trees", flags.open_world_trees,
                       "trees within the open world's streaming radius (default 500000; implies --open-world)");
    add_integer_option(app, "--open-world-frames", flags.open_world_frames,
                       "timed open-world frames (default 300; implies --open-world)");
    add_integer_option(app, "--open-world-changes", flags.open_world_changes,
                       "streaming and LOD changes per frame the viewer's speed is set for (default 2000 per "
                       "500000 trees; implies --open-world)");
    add_integer_option(app, "--open-world-fade-steps", flags.open_world_fade_steps,
                       "steps a coarsening LOD switch fades over (LodBands::fade_steps, default " +
                           std::to_string(LodBands{}.fade_steps) + "; 0: instantaneous switches; implies --open-world)");
    app.add_option("--open-world-fade-bound", flags.open_world_fade_bound,
                   "metres a coarsening tree may deflect and still switch at once, measured with a read of "
                   "its state (LodBands::fade_bound_m; default 0: nothing is read, every coarsening fades, "
                   "as an engine sets it for a world in wind; implies --open-world)");
    app.add_option("--open-world-layout", flags.open_world_layout,
                   "where the open world's instances lie (SimulationConfig::instance_layout): placed (default) "
                   "or packed, for comparison; implies --open-world");
    app.add_option("--case-budget", flags.case_budget,
                   "seconds one case may take: slower cases run fewer steps, forest sizes "
                   "extrapolated past it are skipped (default 20)");
    app.add_flag("--quick", flags.quick, "CI-sized run: paper-5, 5 steps, instances 1,10 (explicit flags win)");
    app.add_option("--json", flags.json_path, "write the results as JSON (docs/benchmarks/README.md)");
    app.add_option("--out", flags.out_stem,
                   "write STEM.json and STEM.md (a header with the commit and date, then the tables), "
                   "replacing them; e.g. docs/benchmarks/nvidia-h100 (also with --render)");
    app.add_option("--commit", flags.commit, "commit id to record in the results");
    app.add_flag("--no-progress", flags.no_progress, "no progress on stderr");
    app.add_option("--render", flags.render, "print the markdown tables of an earlier --json file (and "
                                             "write them with --out) and exit");
}

int run_bench(CLI::App& app) {
    if (!flags.out_stem.empty()) {  // checked before the run: a stem that cannot be written fails at once
        const std::filesystem::path stem(flags.out_stem), folder = stem.parent_path();
        std::error_code ec;
        if (stem.extension() == ".json" || stem.extension() == ".md" || stem.filename().empty())
            return fail_input("--out " + flags.out_stem + ": expected a path without extension, e.g. "
                              "docs/benchmarks/nvidia-h100 (STEM.json and STEM.md are written)");
        if (!folder.empty() && !std::filesystem::is_directory(folder, ec))
            return fail_input("--out " + flags.out_stem + ": the folder " + folder.string() + " does not exist");
    }
    if (!flags.render.empty()) return render_file(flags.render, flags.out_stem);
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
    if (flags.frames < 0 || flags.frames > 100000)
        return fail_input("--frames " + std::to_string(flags.frames) + ": must be in [0, 100000]");
    if (flags.frame_steps < 1 || flags.frame_steps > 64)
        return fail_input("--frame-steps " + std::to_string(flags.frame_steps) + ": must be in [1, 64]");
    flags.open_world |= app.count("--open-world-trees") + app.count("--open-world-frames") +
                            app.count("--open-world-changes") + app.count("--open-world-fade-steps") +
                            app.count("--open-world-fade-bound") + app.count("--open-world-layout") > 0;
    auto world_settings = bench::open_world_settings(flags.open_world_trees, flags.open_world_frames,
                                                     flags.open_world_changes, app.count("--open-world-changes") > 0,
                                                     flags.open_world_fade_steps, flags.open_world_fade_bound);
    if (!world_settings) return fail(world_settings.status());
    const auto world_layout =
        parse_choice(kInstanceLayoutNames, flags.open_world_layout, "--open-world-layout", Spelling::as_is);
    if (!world_layout) return fail(world_layout.status());
    world_settings->layout = *world_layout;
    if (!(flags.case_budget > 0.0) || !std::isfinite(flags.case_budget))
        return fail_input("--case-budget: must be a positive number of seconds");
    const auto forest_composition =
        parse_choice(kCompositionNames, flags.forest_composition, "--forest-composition", Spelling::hyphens);
    if (!forest_composition) return fail(forest_composition.status());
    const auto wind = parse_choice(kWindProfileNames, flags.wind, "--wind", Spelling::as_is);
    if (!wind) return fail(wind.status());
    const auto dynamics_choice = parse_choice(kDynamicsNames, flags.dynamics, "--dynamics", Spelling::as_is);
    if (!dynamics_choice) return fail(dynamics_choice.status());
    if (!(flags.spacing >= 0.0) || !std::isfinite(flags.spacing))
        return fail_input("--spacing: must be a finite number >= 0");

    // Backends: every one named must be known; ones not compiled in are skipped with a note.
    std::vector<BackendRun> backends;
    json skipped_backends = json::array();
    const auto compiled = compiled_backends();
    for (const std::string& name : split_list(flags.backends)) {
        auto kind = parse_backend(name, "--backends", false);
        if (!kind) return fail(kind.status());
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

    auto parsed_counts = count_list(flags.instances, "--instances", 1000000, "counts");
    if (!parsed_counts) return fail(parsed_counts.status());
    const std::vector<uint32_t> counts = std::move(parsed_counts).value();
    auto parsed_joint_counts = count_list(flags.joint_instances, "--joint-instances", 1000000, "counts");
    if (!parsed_joint_counts) return fail(parsed_joint_counts.status());
    const std::vector<uint32_t> joint_counts = std::move(parsed_joint_counts).value();

    auto parsed_frame_counts = count_list(flags.frame_instances, "--frame-instances", 1000000, "counts");
    if (!parsed_frame_counts) return fail(parsed_frame_counts.status());

    auto parsed_depths = count_list(flags.composition_depths, "--composition-depths", 4096, "depths");
    if (!parsed_depths) return fail(parsed_depths.status());
    const std::vector<uint32_t> depths = std::move(parsed_depths).value();

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
    outputs.add_inputs({flags.tree});
    std::optional<size_t> json_file;
    if (!flags.json_path.empty()) {
        auto staged = outputs.stage(flags.json_path, "--json");
        if (!staged) return fail(staged.status());
        json_file = *staged;
    }

    Settings settings{uint32_t(flags.steps), uint32_t(flags.warmup), uint32_t(flags.repeats), flags.case_budget,
                      *forest_composition, *wind};
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
    const json composition_depths =
        depths.empty() ? json::array()
                       : measure_composition_depths(live_backends, depths, settings.steps, settings.warmup,
                                                    settings.case_budget);
    json frames = json::array();
    if (flags.frames > 0) {
        auto tree = flags.tree.empty() ? generate_preset("paper-1") : load_tree(flags.tree);
        if (!tree) return fail(tree.status());
        bench::FrameSettings frame_settings{*parsed_frame_counts, uint32_t(flags.frames), settings.case_budget,
                                            flags.spacing, uint32_t(flags.frame_steps)};
        frames = bench::measure_frames(*tree, live_backends, frame_settings);
    }
    json dynamics = json::array();
    if (*dynamics_choice == Dynamics::coupled) {
        auto tree = flags.tree.empty() ? generate_preset("paper-1") : load_tree(flags.tree);
        if (!tree) return fail(tree.status());
        const std::string name = flags.tree.empty() ? "paper-1" : std::filesystem::path(flags.tree).stem().string();
        dynamics = bench::measure_dynamics(*tree, name, live_backends, flags.quick ? 10u : 10000u, flags.spacing,
                                           settings.steps, settings.warmup, settings.case_budget);
    }
    json open_world = json::array();
    if (flags.open_world) {
        auto tree = flags.tree.empty() ? generate_preset("paper-1") : load_tree(flags.tree);
        if (!tree) return fail(tree.status());
        bench::OpenWorldSettings world = *world_settings;
        world.spacing = flags.spacing;
        world.device_copy_bytes = device_copy_bytes;
        world.host_copy_bytes = host_copy_bytes;
        open_world = bench::measure_open_world(
            *tree, flags.tree.empty() ? "paper-1" : std::filesystem::path(flags.tree).stem().string(), live_backends,
            world);
        for (const json& row : open_world) run.failures += row.contains("failed") ? 1 : 0;
    }
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
                      {"wind", to_string(settings.wind)},
                      {"instances", counts}, {"forest_model", forest_model.name}, {"spacing", flags.spacing},
                      {"forest_layouts", {to_string(kVertexLayouts[0]), to_string(kVertexLayouts[1])}}}},
        {"backends", backends_json},
        {"presets", run.presets},
        {"forest", run.forest},
        {"forest_joints", forest_joints},
        {"live_control", live_control},
        {"frames", frames},
        {"composition_depths", composition_depths},
        {"dynamics", dynamics},
        {"open_world", open_world},
        {"copy_bandwidth", copy},
        {"skipped", run.skipped},
        {"notes", notes},
    };
    if (counts.empty()) {
        document["settings"].erase("forest_model");
        document["settings"].erase("forest_layouts");
    }

    std::fputs(render_tables(document).c_str(), stdout);
    std::fflush(stdout);
    const std::string text = document.dump(2) + "\n";
    if (json_file) {
        Status written = outputs.write(*json_file, text.data(), text.size());
        if (!written) return fail(written);
    }
    if (!flags.out_stem.empty()) {
        Status written = write_page(outputs, flags.out_stem, text, document);
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
