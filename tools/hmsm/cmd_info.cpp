// hmsm info (--tree FILE | --preset NAME) [--grouping ...] [--max-chain-segments K] [--json]
//           [--chains FILE.csv] [--levels B,B,...] [--dynamics paper|coupled] with simulate's
//           parameter flags (they decide the capped chains, the levels' constants and, under
//           coupled, the per-chain constants of docs/model.md 3.13)
#include "cli_common.h"

#include <nlohmann/json.hpp>

#include <algorithm>

namespace hmsm::cli {
namespace {
struct InfoFlags {
    SourceFlags source;
    ModelFlags model;
    Parameters parameters;
    bool json = false;
    std::string chains_csv;
    std::string levels;  ///< joint budgets, comma-separated; empty: kDefaultJointBudgets
} flags;

/// The --levels list: whole integers separated by commas.
Result<std::vector<int32_t>> parse_budgets(const std::string& text) {
    if (text.empty()) return std::vector<int32_t>(std::begin(kDefaultJointBudgets), std::end(kDefaultJointBudgets));
    std::vector<int32_t> budgets;
    size_t start = 0;
    while (true) {
        const size_t comma = text.find(',', start);
        auto budget = parse_integer<int32_t>(text.substr(start, comma - start), "--levels");
        if (!budget) return budget.status();
        budgets.push_back(*budget);
        if (comma == std::string::npos) return budgets;
        start = comma + 1;
    }
}

/// The coupled dynamics' per-chain constants (docs/model.md 3.13) in summary: the trunk's, and
/// the range of the chains' first frequencies.
nlohmann::json coupled_summary(const Hierarchy& h) {
    const ChainDynamics& trunk = h.chains.front().dynamics;
    double low = trunk.frequency[0], high = trunk.frequency[0];
    for (const Chain& chain : h.chains)
        for (double f : chain.dynamics.frequency) {
            low = std::min(low, f);
            high = std::max(high, f);
        }
    return {{"trunk",
             {{"frequency_hz", {trunk.frequency[0], trunk.frequency[1]}},
              {"mass_kg", trunk.mass},
              {"subtree_mass_kg", trunk.subtree_mass},
              {"inertia_kg_m2", {trunk.inertia[0], trunk.inertia[1]}},
              {"stiffness_n_m_per_rad", {trunk.stiffness[0], trunk.stiffness[1]}},
              {"damping_n_m_s_per_rad", {trunk.damping[0], trunk.damping[1]}},
              {"subtree_drag_area_m2", trunk.subtree_drag_area}}},
            {"chain_frequency_min_hz", low},
            {"chain_frequency_max_hz", high}};
}

void print_coupled_summary(const nlohmann::json& c) {
    const nlohmann::json& t = c["trunk"];
    std::printf("coupled trunk    f0 %.4f / %.4f Hz (x / z), m %.4g kg, m_sub %.4g kg, A_sub %.4g m^2\n",
                t["frequency_hz"][0].get<double>(), t["frequency_hz"][1].get<double>(), t["mass_kg"].get<double>(),
                t["subtree_mass_kg"].get<double>(), t["subtree_drag_area_m2"].get<double>());
    std::printf("                 I %.4g / %.4g kg m^2, K %.4g / %.4g N m/rad, D %.4g / %.4g N m s/rad\n",
                t["inertia_kg_m2"][0].get<double>(), t["inertia_kg_m2"][1].get<double>(),
                t["stiffness_n_m_per_rad"][0].get<double>(), t["stiffness_n_m_per_rad"][1].get<double>(),
                t["damping_n_m_s_per_rad"][0].get<double>(), t["damping_n_m_s_per_rad"][1].get<double>());
    std::printf("coupled chains   f0 %.4f .. %.4f Hz\n", c["chain_frequency_min_hz"].get<double>(),
                c["chain_frequency_max_hz"].get<double>());
}
}  // namespace

void register_info_flags(CLI::App& app) {
    add_source_flags(app, flags.source, false);
    app.add_option("--grouping", flags.model.grouping, "chain grouping: direction or width");
    add_integer_option(app, "--max-chain-segments", flags.model.options.max_chain_segments,
                       "cut chains after K nodes (0 = never)");
    add_integer_option(app, "--ring-sides", flags.model.options.ring_sides, "vertices per ring (default 8)");
    app.add_option("--dynamics", flags.model.dynamics,
                   "paper (default) or coupled: coupled also prints its per-chain constants in summary "
                   "(docs/model.md 3.13)");
    // The parameters decide which chains the frequency cap raises ("capped chains").
    add_parameter_flags(app, flags.parameters);
    app.add_flag("--json", flags.json, "print JSON instead of text");
    app.add_option("--chains", flags.chains_csv, "write chain,parent,depth,attach_node,nodes CSV");
    app.add_option("--levels", flags.levels,
                   "joint budgets of the levels of detail, comma-separated (default 256,64,16,1)");
}

int run_info(CLI::App& app) {
    auto options = model_options(flags.model);
    if (!options) return fail(options.status());
    Status parameters_ok = validate(flags.parameters);
    if (!parameters_ok) return fail(parameters_ok);
    auto budgets = parse_budgets(flags.levels);
    if (!budgets) return fail(budgets.status());
    auto scene = load_scene(flags.source, app);
    if (!scene) return fail(scene.status());
    const TreeModel& tree = scene->models[0];
    StagedOutputs outputs;
    outputs.add_inputs({flags.source.tree});
    std::optional<size_t> chains_file;
    if (!flags.chains_csv.empty()) {
        auto staged = outputs.stage(flags.chains_csv, "--chains");
        if (!staged) return fail(staged.status());
        chains_file = *staged;
    }
    auto hierarchy = build_hierarchy(tree, *options, flags.parameters);
    if (!hierarchy) return fail(hierarchy.status());
    MeshTemplate mesh = build_mesh(tree, *hierarchy, *options);
    auto levels = build_levels(tree, *hierarchy, flags.parameters, *budgets);
    if (!levels) return fail_input("--levels: " + levels.status().message());

    if (chains_file) {
        std::string csv = "chain,parent,depth,attach_node,nodes\n";
        for (size_t c = 0; c < hierarchy->chains.size(); ++c) {
            const Chain& chain = hierarchy->chains[c];
            csv += std::to_string(c) + "," + std::to_string(chain.parent) + "," +
                   std::to_string(chain.depth) + "," + std::to_string(chain.attach_node) + ",";
            for (size_t j = 0; j < chain.members.size(); ++j)
                csv += (j ? " " : "") + std::to_string(chain.members[j]);
            csv += "\n";
        }
        Status written = outputs.write(*chains_file, csv.data(), csv.size());
        if (!written) return fail(written);
    }
    Status committed = outputs.commit();
    if (!committed) return fail(committed);

    const auto& h = *hierarchy;
    if (flags.json) {
        nlohmann::json j;
        j["nodes"] = tree.nodes.size();
        j["chains"] = h.chains.size();
        j["max_depth"] = h.max_depth;
        j["chains_per_depth"] = h.chains_per_depth;
        j["mesh_vertices"] = mesh.vertices.size();
        j["triangles"] = mesh.triangle_count();
        j["leaves"] = tree.leaves.size();
        j["height_m"] = tree_height(tree);
        j["capped_chains"] = h.capped_chain_count;
        j["trunk_frequency_hz"] = levels->front().full_trunk_frequency_hz;
        if (options->dynamics == Dynamics::coupled) j["coupled"] = coupled_summary(h);
        j["levels"] = nlohmann::json::array();
        for (const DetailLevel& level : *levels)
            j["levels"].push_back({{"budget", level.budget},
                                   {"joints", level.joint_count()},
                                   {"max_depth", level.hierarchy.max_depth},
                                   {"trunk_frequency_hz", level.trunk_frequency_hz},
                                   {"frequency_ratio", level.frequency_ratio()},
                                   {"geometric_error_m", level.geometric_error_m}});
        std::printf("%s\n", j.dump(2).c_str());
    } else {
        std::printf("nodes            %zu\n", tree.nodes.size());
        std::printf("chains           %zu\n", h.chains.size());
        std::printf("max depth        %d\n", h.max_depth);
        std::printf("chains per depth");
        for (int32_t n : h.chains_per_depth) std::printf(" %d", n);
        std::printf("\nmesh vertices    %zu\n", mesh.vertices.size());
        std::printf("triangles        %u\n", mesh.triangle_count());
        std::printf("leaves           %zu\n", tree.leaves.size());
        std::printf("height           %.3f m\n", tree_height(tree));
        std::printf("capped chains    %d\n", h.capped_chain_count);
        std::printf("trunk frequency  %.4f Hz\n", levels->front().full_trunk_frequency_hz);
        if (options->dynamics == Dynamics::coupled) print_coupled_summary(coupled_summary(h));
        std::printf("levels           budget  joints  f0 ratio  geometric error\n");
        const double height = tree_height(tree);
        for (const DetailLevel& level : *levels)
            std::printf("                 %6d  %6d  %8.4f  %.4f m (%.3f %% of height)\n", level.budget,
                        level.joint_count(), level.frequency_ratio(), level.geometric_error_m,
                        height > 0.0 ? 100.0 * level.geometric_error_m / height : 0.0);
    }
    return kExitOk;
}

}  // namespace hmsm::cli
