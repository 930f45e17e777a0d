// hmsm import (--treeqsm FILE | --simpleforest FILE) --out TREE.json [--leaves N --leaf-seed S]
// [--json]: a real tree from a laser-scan cylinder model (docs/model.md 4, docs/real-trees.md).
#include "cli_common.h"

#include <nlohmann/json.hpp>

namespace hmsm::cli {
namespace {
struct ImportFlags {
    std::string treeqsm, simpleforest, out;
    uint64_t leaves = 0;
    uint64_t leaf_seed = 1;
    std::vector<double> leaf_size{0.08, 0.12};
    bool json = false;
} flags;
}  // namespace

void register_import_flags(CLI::App& app) {
    auto* qsm = app.add_option("--treeqsm", flags.treeqsm,
                               "TreeQSM cylinder table: text export with header (17 columns) or v2.3 text (15)");
    auto* sf = app.add_option("--simpleforest", flags.simpleforest, "SimpleForest QSM CSV");
    qsm->excludes(sf);
    app.add_option("--out", flags.out, "output hmsm-tree JSON file")->required();
    app.add_option("--leaves", flags.leaves, "scatter N leaf cards on the thinnest branches (default 0)");
    app.add_option("--leaf-seed", flags.leaf_seed, "seed of the leaf scatter (default 1)");
    app.add_option("--leaf-size", flags.leaf_size, "leaf card width and height in metres (default 0.08 0.12)")
        ->expected(2);
    app.add_flag("--json", flags.json, "print the summary as JSON");
}

int run_import(CLI::App&) {
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
        std::printf("%s\n", j.dump(2).c_str());
    } else {
        std::printf("format             %s\n", to_string(s.format));
        std::printf("cylinders          %zu\n", s.cylinders);
        std::printf("nodes              %zu (%zu tiny cylinder ends merged)\n", tree.nodes.size(), s.merged_nodes);
        std::printf("leaves             %zu\n", tree.leaves.size());
        std::printf("height             %.3f m\n", s.height);
        std::printf("trunk base radius  %.4f m\n", s.base_radius);
    }
    return kExitOk;
}

}  // namespace hmsm::cli
