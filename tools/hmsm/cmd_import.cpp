// hmsm import (--treeqsm FILE | --simpleforest FILE) --out TREE.json [--leaves N --leaf-seed S]
// [--species NAME] [--leaf-state on|off] [--json]: a real tree from a laser-scan cylinder model
// (docs/model.md 4, docs/real-trees.md), with the species' wood and the leaf state written into
// the tree file (hmsm-tree version 2) for the coupled dynamics.
#include "cli_common.h"

#include <nlohmann/json.hpp>

namespace hmsm::cli {
namespace {
struct ImportFlags {
    std::string treeqsm, simpleforest, out;
    uint64_t leaves = 0;
    uint64_t leaf_seed = 1;
    std::vector<double> leaf_size{0.08, 0.12};
    std::string species, leaf_state;
    bool list_species = false;
    bool json = false;
} flags;
}  // namespace

void register_import_flags(CLI::App& app) {
    auto* qsm = app.add_option("--treeqsm", flags.treeqsm,
                               "TreeQSM cylinder table: text export with header (17 columns) or v2.3 text (15)");
    auto* sf = app.add_option("--simpleforest", flags.simpleforest, "SimpleForest QSM CSV");
    qsm->excludes(sf);
    app.add_option("--out", flags.out, "output hmsm-tree JSON file");
    app.add_option("--species", flags.species,
                   "wood species preset (green modulus and density, data/species.json); --list-species names them");
    app.add_flag("--list-species", flags.list_species, "print the species presets and their sources, then exit");
    app.add_option("--leaf-state", flags.leaf_state, "on or off: the tree's leaf state under the coupled dynamics");
    app.add_option("--leaves", flags.leaves, "scatter N leaf cards on the thinnest branches (default 0)");
    app.add_option("--leaf-seed", flags.leaf_seed, "seed of the leaf scatter (default 1)");
    app.add_option("--leaf-size", flags.leaf_size, "leaf card width and height in metres (default 0.08 0.12)")
        ->expected(2);
    app.add_flag("--json", flags.json, "print the summary as JSON");
}

int run_import(CLI::App&) {
    if (flags.list_species) {
        for (const SpeciesPreset& s : species_presets())
            std::printf("%-20s %-9s E %5.1f GPa  density %6.1f kg/m^3  %s (%s); %s\n", s.name.c_str(),
                        s.kind.c_str(), s.modulus * 1e-9, s.density, s.common_name.c_str(),
                        s.scientific_name.c_str(), s.citation.c_str());
        return kExitOk;
    }
    if (flags.out.empty()) return fail_input("--out FILE is required");
    std::optional<TreeMaterial> material;
    if (!flags.species.empty()) {
        auto found = species_material(flags.species);
        if (!found) return fail_input("--species: " + found.status().message());
        material = *found;
    }
    std::optional<bool> leaves_on;
    if (!flags.leaf_state.empty()) {
        if (flags.leaf_state != "on" && flags.leaf_state != "off")
            return fail_input("--leaf-state must be on or off, got \"" + detail::quote_input(flags.leaf_state) + "\"");
        leaves_on = flags.leaf_state == "on";
    }
    if (flags.treeqsm.empty() && flags.simpleforest.empty())
        return fail_input("give the cylinder model with --treeqsm FILE or --simpleforest FILE");
    // The output is checked (not the input, a regular file, not a link) before the import runs.
    StagedOutputs outputs;
    outputs.add_inputs({flags.treeqsm, flags.simpleforest});
    auto out_file = outputs.stage(flags.out, "--out");
    if (!out_file) return fail(out_file.status());
    auto imported = flags.treeqsm.empty() ? import_simpleforest(flags.simpleforest)
                                          : import_treeqsm(flags.treeqsm);
    if (!imported) return fail(imported.status());
    TreeModel& tree = imported->tree;
    tree.material = material;
    tree.leaves_on = leaves_on;
    Status leaves = scatter_leaves(tree, flags.leaves, flags.leaf_seed, flags.leaf_size[0], flags.leaf_size[1]);
    if (!leaves) return fail(leaves);
    Status valid = validate_tree(tree);
    if (!valid) return fail(valid);
    const std::string text = tree_to_json(tree);
    Status saved = outputs.write(*out_file, text.data(), text.size());
    if (saved) saved = outputs.commit();
    if (!saved) return fail(saved);
    const ImportSummary& s = imported->summary;
    if (flags.json) {
        nlohmann::json j;
        j["format"] = to_string(s.format);
        j["cylinders"] = s.cylinders;
        j["nodes"] = tree.nodes.size();
        j["merged_nodes"] = s.merged_nodes;
        j["leaves"] = tree.leaves.size();
        j["height_m"] = s.height;
        j["trunk_base_radius_m"] = s.base_radius;
        if (material) j["material"] = {{"species", material->species}, {"modulus_pa", material->modulus},
                                       {"density_kg_m3", material->density}};
        if (leaves_on) j["leaves_on"] = *leaves_on;
        std::printf("%s\n", j.dump(2).c_str());
    } else {
        std::printf("format             %s\n", to_string(s.format));
        std::printf("cylinders          %zu\n", s.cylinders);
        std::printf("nodes              %zu (%zu tiny cylinder ends merged)\n", tree.nodes.size(), s.merged_nodes);
        std::printf("leaves             %zu\n", tree.leaves.size());
        std::printf("height             %.3f m\n", s.height);
        std::printf("trunk base radius  %.4f m\n", s.base_radius);
        if (material)
            std::printf("wood               %s: E %.3g Pa, density %.4g kg/m^3\n", material->species.c_str(),
                        material->modulus, material->density);
        if (leaves_on) std::printf("leaf state         %s\n", *leaves_on ? "on" : "off");
    }
    return kExitOk;
}

}  // namespace hmsm::cli
