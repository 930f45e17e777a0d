// hmsm simulate: runs the passes --outputs needs (all seven by default) for --steps steps and writes the requested dumps.
#include "cli_common.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cinttypes>

namespace hmsm::cli {
namespace {
struct SimulateFlags {
    SourceFlags source;
    ModelFlags model;
    Parameters parameters;
    WindFlags wind;
    std::string backend = "auto";
    std::string composition = "pointer-jumping";
    std::string vertex_layout = "separate";
    int64_t steps = 120;
    std::string dump_nodes, dump_vertices, report;
    std::string outputs = "all";
    std::string dump_chains;
} flags;

/// --dump-chains: instance,chain,ox,oy,oz,r00,r10,r20,r01,r11,r21,r02,r12,r22 (O_c, then R_c
/// column by column; rIJ = row I, column J), every instance's chains in chain order, %.17g.
Result<std::string> chain_csv(const Simulation& sim) {
    std::vector<double> joints;
    HMSM_TRY(sim.read(Output::joint_matrices, joints));
    std::string csv = "instance,chain,ox,oy,oz,r00,r10,r20,r01,r11,r21,r02,r12,r22\n";
    char line[512];
    uint64_t element = 0;
    const auto instances = sim.instances();
    for (size_t i = 0; i < instances.size(); ++i) {
        const size_t chains = sim.hierarchy(instances[i].model).chains.size();
        for (size_t c = 0; c < chains; ++c, ++element) {
            const double* m = &joints[12 * element];  // rows (R row r, O_r)
            int n = std::snprintf(line, sizeof line, "%zu,%zu,%.17g,%.17g,%.17g", i, c, m[3], m[7], m[11]);
            for (int col = 0; col < 3; ++col)
                for (int row = 0; row < 3; ++row)
                    n += std::snprintf(line + n, sizeof line - size_t(n), ",%.17g", m[4 * row + col]);
            csv.append(line, size_t(n));
            csv += '\n';
        }
    }
    return csv;
}

std::string node_csv(const Simulation& sim, const std::vector<double>& xyz) {
    std::string csv = "instance,node,x,y,z\n";
    char line[160];
    uint64_t element = 0;
    const Scene& scene = sim.scene();
    for (size_t i = 0; i < scene.instances.size(); ++i) {
        size_t nodes = scene.models[scene.instances[i].model].nodes.size();
        for (size_t n = 0; n < nodes; ++n, ++element) {
            std::snprintf(line, sizeof line, "%zu,%zu,%.9g,%.9g,%.9g\n", i, n, xyz[3 * element],
                          xyz[3 * element + 1], xyz[3 * element + 2]);
            csv += line;
        }
    }
    return csv;
}

}  // namespace

void register_simulate_flags(CLI::App& app) {
    add_source_flags(app, flags.source, true);
    add_model_flags(app, flags.model);
    add_parameter_flags(app, flags.parameters);
    add_wind_flags(app, flags.wind);
    app.add_option("--backend", flags.backend, "cpu, cpu-parallel, cpu64, vulkan, cuda or auto (default)");
    app.add_option("--composition", flags.composition,
                   "passes 3 and 5: pointer-jumping (default: the paper's rounds, per round or in one "
                   "dispatch by scene size), pointer-jumping-per-round, pointer-jumping-in-dispatch "
                   "or level-by-level");
    app.add_option("--vertex-layout", flags.vertex_layout,
                   "device layout of the mesh vertices: separate (default; position and normal "
                   "vec4) or packed (the normal octahedral-encoded in the position's w)");
    app.add_option("--steps", flags.steps, "time steps to run (default 120)");
    app.add_option("--dump-nodes", flags.dump_nodes, "CSV instance,node,x,y,z after the last step");
    app.add_option("--dump-vertices", flags.dump_vertices, "float32 xyz per mesh vertex");
    app.add_option("--dump-chains", flags.dump_chains,
                   "CSV instance,chain,ox,oy,oz,r00,r10,r20,r01,r11,r21,r02,r12,r22 after the last step");
    app.add_option("--outputs", flags.outputs,
                   "what each step produces: joints (passes 1-5: joint matrices), nodes (1-6: plus "
                   "node positions) or all (default; 1-7: plus mesh vertices)");
    app.add_option("--report", flags.report, "JSON report: backend, device, counts, times");
}

int run_simulate(CLI::App& app) {
    SimulationConfig config;
    auto backend = parse_backend_kind(flags.backend);
    if (!backend)
        return fail_input("--backend '" + flags.backend + "': expected cpu, cpu-parallel, cpu64, vulkan, cuda or auto");
    config.backend = *backend;
    config.profile_passes = !flags.report.empty();  // per-pass times only feed the report
    std::string composition = flags.composition;
    std::replace(composition.begin(), composition.end(), '-', '_');
    if (auto parsed = parse_composition(composition)) config.composition = *parsed;
    else return fail_input("--composition '" + flags.composition +
                           "': expected pointer-jumping, pointer-jumping-per-round, pointer-jumping-in-dispatch or "
                           "level-by-level");
    auto vertex_layout = parse_vertex_layout(flags.vertex_layout);
    if (!vertex_layout)
        return fail_input("--vertex-layout '" + flags.vertex_layout + "': expected separate or packed");
    config.vertex_layout = *vertex_layout;
    auto produced = parse_outputs(flags.outputs);
    if (!produced) return fail_input("--outputs '" + flags.outputs + "': expected joints, nodes or all");
    config.outputs = *produced;
    if (!flags.dump_nodes.empty() && config.outputs == Outputs::joints)
        return fail_input("--dump-nodes needs node positions: --outputs nodes or all, not joints");
    if (!flags.dump_vertices.empty() && config.outputs != Outputs::all)
        return fail_input("--dump-vertices needs mesh vertices: --outputs all, not " + flags.outputs);
    if (flags.steps < 0) return fail_input("--steps " + std::to_string(flags.steps) + ": must be >= 0");
    auto options = model_options(flags.model);
    if (!options) return fail(options.status());
    config.model = *options;
    config.parameters = flags.parameters;
    Status parameters_ok = validate(config.parameters);
    if (!parameters_ok) return fail(parameters_ok);
    auto wind = wind_options(flags.wind);
    if (!wind) return fail(wind.status());
    config.wind = *wind;
    auto scene = load_scene(flags.source, app);
    if (!scene) return fail(scene.status());

    StagedOutputs outputs;
    std::optional<size_t> nodes_file, vertices_file, report_file, chains_file;
    for (auto [path, flag, slot] : {std::tuple{&flags.dump_nodes, "--dump-nodes", &nodes_file},
                                    std::tuple{&flags.dump_chains, "--dump-chains", &chains_file},
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

    PassTimes total;
    const auto start = std::chrono::steady_clock::now();
    for (int64_t done = 0; done < flags.steps;) {
        uint32_t chunk = uint32_t(std::min<int64_t>(flags.steps - done, 240));
        Status stepped = sim.step(chunk);
        if (!stepped) return fail(stepped);
        PassTimes t = sim.pass_times();
        for (uint32_t p = 0; p < kPassCount; ++p) total.seconds[p] += t.seconds[p];
        total.steps += t.steps;
        done += chunk;
    }
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
        r["composition"] = flags.composition;
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
