// hmsm simulate: runs the seven passes for --steps steps, driven by the wind flags and an optional
// schedule, and writes the requested dumps and trace (docs/model.md 5).
#include "cli_common.h"
#include "step_progress.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cinttypes>
#include <cstdio>

namespace hmsm::cli {
namespace {
struct SimulateFlags {
    SourceFlags source;
    ModelFlags model;
    Parameters parameters;
    WindFlags wind;
    std::string backend = "auto";
    std::string composition = "automatic";
    std::string vertex_layout = "separate";
    int64_t steps = 120;
    std::string dump_nodes, dump_chains, dump_vertices, report, trace, trace_nodes;
    std::string outputs = "all";
    bool no_progress = false;
} flags;

/// Element offset of each instance of the current list in an instance-major node or chain
/// output (`per_model`: count per model).
std::vector<uint64_t> offsets(const Simulation& sim, const std::vector<uint64_t>& per_model) {
    std::vector<uint64_t> first;
    uint64_t at = 0;
    for (const Instance& inst : sim.instances()) {
        first.push_back(at);
        at += per_model[inst.model];
    }
    return first;
}

std::vector<uint64_t> node_counts(const Simulation& sim) {
    std::vector<uint64_t> counts;
    for (const TreeModel& m : sim.scene().models) counts.push_back(m.nodes.size());
    return counts;
}

void append(std::string& csv, const char* format, auto... values) {
    char line[512];
    int n = std::snprintf(line, sizeof line, format, values...);
    csv.append(line, size_t(n));
}

/// instance,node,x,y,z for every node of every instance (current list, input order).
std::string node_csv(const Simulation& sim, const std::vector<double>& xyz) {
    std::string csv = "instance,node,x,y,z\n";
    const std::vector<uint64_t> counts = node_counts(sim);
    uint64_t element = 0;
    const auto instances = sim.instances();
    for (size_t i = 0; i < instances.size(); ++i)
        for (uint64_t n = 0; n < counts[instances[i].model]; ++n, ++element)
            append(csv, "%zu,%" PRIu64 ",%.17g,%.17g,%.17g\n", i, n, xyz[3 * element], xyz[3 * element + 1],
                   xyz[3 * element + 2]);
    return csv;
}

/// instance,chain,ox,oy,oz,r00,r10,r20,r01,r11,r21,r02,r12,r22: O_c, then R_c column by column.
Result<std::string> chain_csv(const Simulation& sim) {
    std::vector<double> origins, rotations;
    HMSM_TRY(sim.read(Output::chain_origins, origins));
    HMSM_TRY(sim.read(Output::chain_rotations, rotations));  // column-major: r00 r10 r20 r01 ...
    std::string csv = "instance,chain,ox,oy,oz,r00,r10,r20,r01,r11,r21,r02,r12,r22\n";
    uint64_t element = 0;
    const auto instances = sim.instances();
    for (size_t i = 0; i < instances.size(); ++i) {
        const size_t chains = sim.hierarchy(instances[i].model).chains.size();
        for (size_t c = 0; c < chains; ++c, ++element) {
            const double* o = &origins[3 * element];
            const double* r = &rotations[9 * element];
            append(csv, "%zu,%zu,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", i, c,
                   o[0], o[1], o[2], r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8]);
        }
    }
    return csv;
}

/// The nodes --trace-nodes names, per model: `top` (the highest rest y, lowest index on ties)
/// or I,J,... (distinct indices that exist in every model).
Result<std::vector<std::vector<uint32_t>>> trace_nodes(const std::string& text, const Scene& scene) {
    std::vector<std::vector<uint32_t>> per_model(scene.models.size());
    if (text == "top") {
        for (size_t m = 0; m < scene.models.size(); ++m) {
            const auto& nodes = scene.models[m].nodes;
            uint32_t top = 0;
            for (uint32_t n = 1; n < nodes.size(); ++n)
                if (nodes[n].position.y > nodes[top].position.y) top = n;
            per_model[m].push_back(top);
        }
        return per_model;
    }
    std::vector<uint32_t> list;
    size_t at = 0;
    while (true) {
        const size_t comma = text.find(',', at);
        const std::string item = text.substr(at, comma == std::string::npos ? std::string::npos : comma - at);
        auto index = parse_integer<uint32_t>(item, "--trace-nodes");
        if (!index)
            return Status{ErrorCode::invalid_argument,
                          "--trace-nodes '" + detail::quote_input(text) + "': expected top or node indices I,J,... (" +
                              (item.empty() ? std::string("empty item")
                                            : "'" + detail::quote_input(item) + "' is not an index") +
                              ")"};
        if (std::find(list.begin(), list.end(), *index) != list.end())
            return Status{ErrorCode::invalid_argument,
                          "--trace-nodes '" + detail::quote_input(text) + "': node " + item + " is listed twice"};
        for (size_t m = 0; m < scene.models.size(); ++m)
            if (*index >= scene.models[m].nodes.size())
                return Status{ErrorCode::invalid_argument,
                              "--trace-nodes: node " + item + " does not exist in model '" +
                                  detail::quote_input(scene.model_names[m]) + "' (" +
                                  std::to_string(scene.models[m].nodes.size()) + " nodes)"};
        list.push_back(*index);
        if (comma == std::string::npos) break;
        at = comma + 1;
    }
    per_model.assign(scene.models.size(), list);
    return per_model;
}

/// step,instance,node,x,y,z rows of one step for the traced nodes of every instance.
void append_trace(std::string& csv, uint64_t step, const Simulation& sim, const std::vector<double>& xyz,
                  const std::vector<std::vector<uint32_t>>& nodes) {
    const std::vector<uint64_t> first = offsets(sim, node_counts(sim));
    const auto instances = sim.instances();
    for (size_t i = 0; i < instances.size(); ++i)
        for (uint32_t n : nodes[instances[i].model]) {
            const double* p = &xyz[3 * (first[i] + n)];
            append(csv, "%" PRIu64 ",%zu,%u,%.17g,%.17g,%.17g\n", step, i, n, p[0], p[1], p[2]);
        }
}

}  // namespace

void register_simulate_flags(CLI::App& app) {
    add_source_flags(app, flags.source, true);
    add_model_flags(app, flags.model);
    add_parameter_flags(app, flags.parameters);
    add_wind_flags(app, flags.wind);
    app.add_option("--backend", flags.backend, backend_choices(BackendKind::automatic));
    app.add_option("--composition", flags.composition,
                   "passes 3 and 5 (docs/cli.md): " +
                       choices(kCompositionNames, Spelling::hyphens, Composition::automatic) +
                       "; automatic is path-walk on a GPU, else pointer-jumping");
    app.add_option("--vertex-layout", flags.vertex_layout,
                   "device layout of the mesh vertices: " +
                       choices(kVertexLayoutNames, Spelling::as_is, VertexLayout::separate) +
                       "; separate: position and normal vec4, packed: the normal octahedral-encoded "
                       "in the position's w");
    add_integer_option(app, "--steps", flags.steps, "time steps to run (default 120)");
    app.add_option("--dump-nodes", flags.dump_nodes, "CSV instance,node,x,y,z after the last step");
    app.add_option("--dump-chains", flags.dump_chains,
                   "CSV instance,chain,ox,oy,oz,r00,r10,r20,r01,r11,r21,r02,r12,r22 (joint matrices) after "
                   "the last step");
    app.add_option("--trace", flags.trace, "CSV step,instance,node,x,y,z after every step (with --trace-nodes)");
    app.add_option("--trace-nodes", flags.trace_nodes,
                   "nodes --trace follows in every instance: top (per model the highest) or I,J,...");
    app.add_option("--dump-vertices", flags.dump_vertices, "float32 xyz per mesh vertex");
    app.add_option("--outputs", flags.outputs,
                   "what each step produces: " + choices(kOutputsNames, Spelling::as_is, Outputs::all) +
                       "; joints: passes 1-5, joint matrices; nodes: 1-6, plus node positions; all: "
                       "1-7, plus mesh vertices");
    app.add_option("--report", flags.report, "JSON report: backend, device, counts, times");
    app.add_flag("--no-progress", flags.no_progress, "no progress on stderr");
}

int run_simulate(CLI::App& app) {
    SimulationConfig config;
    auto backend = parse_backend(flags.backend, "--backend");
    if (!backend) return fail(backend.status());
    config.backend = *backend;
    config.profile_passes = !flags.report.empty();  // per-pass times only feed the report
    auto composition = parse_choice(kCompositionNames, flags.composition, "--composition", Spelling::hyphens);
    if (!composition) return fail(composition.status());
    config.composition = *composition;
    auto vertex_layout = parse_choice(kVertexLayoutNames, flags.vertex_layout, "--vertex-layout", Spelling::as_is);
    if (!vertex_layout) return fail(vertex_layout.status());
    config.vertex_layout = *vertex_layout;
    auto produced = parse_choice(kOutputsNames, flags.outputs, "--outputs", Spelling::as_is);
    if (!produced) return fail(produced.status());
    config.outputs = *produced;
    if (!flags.dump_nodes.empty() && config.outputs == Outputs::joints)
        return fail_input("--dump-nodes needs node positions: --outputs nodes or all, not joints");
    if (!flags.trace.empty() && config.outputs == Outputs::joints)
        return fail_input("--trace needs node positions: --outputs nodes or all, not joints");
    if (!flags.dump_vertices.empty() && config.outputs != Outputs::all)
        return fail_input("--dump-vertices needs mesh vertices: --outputs all, not " + flags.outputs);
    if (flags.steps < 0) return fail_input("--steps " + std::to_string(flags.steps) + ": must be >= 0");
    Status shared = apply_shared_options(config, flags.model, flags.parameters, flags.wind);
    if (!shared) return fail(shared);
    auto schedule = read_schedule_option(flags.wind);
    if (!schedule) return fail(schedule.status());
    auto scene = load_scene(flags.source, app, &config.model, scheduled_models(*schedule));
    if (!scene) return fail(scene.status());
    if (Status valid = check_schedule_option(flags.wind, *schedule, *scene, config.wind); !valid) return fail(valid);
    if (flags.trace.empty() != flags.trace_nodes.empty())
        return fail_input("--trace FILE and --trace-nodes top|I,J,... go together");
    std::vector<std::vector<uint32_t>> traced;
    if (!flags.trace.empty()) {
        auto nodes = trace_nodes(flags.trace_nodes, *scene);
        if (!nodes) return fail(nodes.status());
        traced = std::move(nodes).value();
    }

    StagedOutputs outputs;
    outputs.add_inputs({flags.source.tree, flags.source.forest, flags.wind.schedule});
    std::optional<size_t> nodes_file, chains_file, trace_file, vertices_file, report_file;
    for (auto [path, flag, slot] : {std::tuple{&flags.dump_nodes, "--dump-nodes", &nodes_file},
                                    std::tuple{&flags.dump_chains, "--dump-chains", &chains_file},
                                    std::tuple{&flags.trace, "--trace", &trace_file},
                                    std::tuple{&flags.dump_vertices, "--dump-vertices", &vertices_file},
                                    std::tuple{&flags.report, "--report", &report_file}}) {
        if (path->empty()) continue;
        auto staged = outputs.stage(*path, flag);
        if (!staged) return fail(staged.status());
        *slot = *staged;
    }

    auto created = Simulation::create(*scene, config);
    if (!created) return fail(created.status());
    Simulation& sim = **created;
    if (config.backend == BackendKind::automatic)
        std::fprintf(stderr, "hmsm: backend auto picked %s (%s)\n", to_string(sim.backend_kind()),
                     sim.device_name().c_str());

    // Schedule events apply before their step; the steps between events (and between traced
    // rows) run as one batch.
    const uint64_t steps = uint64_t(flags.steps);
    PassTimes total;
    StepProgress progress(steps, !flags.no_progress);
    std::string trace_csv = trace_file ? "step,instance,node,x,y,z\n" : "";
    std::vector<double> xyz;
    const auto start = std::chrono::steady_clock::now();
    for (uint64_t done = 0; done < steps;) {
        uint64_t chunk = std::min<uint64_t>(steps - done, 240);
        if (*schedule) {
            Status applied = apply_schedule_events(**schedule, done + 1, sim);
            if (!applied) return fail(applied);
            if (auto next = next_schedule_step(**schedule, done + 1)) chunk = std::min(chunk, *next - (done + 1));
        }
        if (trace_file) chunk = 1;
        Status stepped = sim.step(uint32_t(chunk));
        if (!stepped) return fail(stepped);
        PassTimes t = sim.pass_times();
        for (uint32_t p = 0; p < kPassCount; ++p) total.seconds[p] += t.seconds[p];
        total.steps += t.steps;
        done += chunk;
        if (trace_file) {
            Status read = sim.read(Output::node_positions, xyz);
            if (!read) return fail(read);
            append_trace(trace_csv, done, sim, xyz, traced);
            if (trace_csv.size() > (1u << 20)) {  // flush the rows in pieces
                Status written = outputs.write(*trace_file, trace_csv.data(), trace_csv.size());
                if (!written) return fail(written);
                trace_csv.clear();
            }
        }
        progress.update(done);
    }
    progress.finish();
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

    if (nodes_file) {
        std::vector<double> xyz;
        Status read = sim.read(Output::node_positions, xyz);
        if (!read) return fail(read);
        std::string csv = node_csv(sim, xyz);
        Status written = outputs.write(*nodes_file, csv.data(), csv.size());
        if (!written) return fail(written);
    }
    if (chains_file) {
        auto csv = chain_csv(sim);
        if (!csv) return fail(csv.status());
        Status written = outputs.write(*chains_file, csv->data(), csv->size());
        if (!written) return fail(written);
    }
    if (trace_file) {
        Status written = outputs.write(*trace_file, trace_csv.data(), trace_csv.size());
        if (!written) return fail(written);
    }
    if (vertices_file) {
        std::vector<float> xyz;
        Status read = sim.read(Output::vertex_positions, xyz);
        if (!read) return fail(read);
        Status written = outputs.write(*vertices_file, xyz.data(), xyz.size() * sizeof(float));
        if (!written) return fail(written);
    }
    if (report_file) {
        nlohmann::json r;
        r["backend"] = to_string(sim.backend_kind());
        r["device"] = sim.device_name();
        // automatic resolved, as the flag spells it
        r["composition"] = spelled(to_string(sim.config().composition), Spelling::hyphens);
        r["vertex_layout"] = to_string(config.vertex_layout);
        r["outputs"] = to_string(config.outputs);
        r["instances"] = sim.instance_count();
        r["models"] = sim.scene().models.size();
        r["nodes"] = sim.node_count();
        r["chains"] = sim.chain_count();
        r["mesh_vertices"] = sim.vertex_count();
        r["jump_rounds"] = sim.jump_rounds();
        r["capped_chains"] = sim.capped_chain_count();
        r["steps"] = flags.steps;
        r["dt"] = config.parameters.dt;
        r["wall_seconds"] = wall;
        r["steps_per_second"] = wall > 0.0 ? double(flags.steps) / wall : 0.0;
        nlohmann::json passes = nlohmann::json::object();
        for (Pass p : kAllPasses) passes[std::string(pass_name(p))] = total.seconds[uint32_t(p)];
        r["pass_device_seconds"] = passes;
        r["device_seconds_total"] = total.total();
        std::string text = r.dump(2) + "\n";
        Status written = outputs.write(*report_file, text.data(), text.size());
        if (!written) return fail(written);
    }
    Status committed = outputs.commit();
    if (!committed) return fail(committed);
    std::fprintf(stderr, "hmsm: %" PRId64 " steps of %" PRIu64 " instance(s) on %s in %.3f s\n",
                 flags.steps, sim.instance_count(), to_string(sim.backend_kind()), wall);
    return kExitOk;
}

}  // namespace hmsm::cli
