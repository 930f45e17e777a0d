// hmsm generate --preset NAME [--seed S] --out FILE
#include "cli_common.h"

namespace hmsm::cli {
namespace {
struct GenerateFlags {
    std::string preset, out;
    uint64_t seed = 0;
} flags;
}  // namespace

void register_generate_flags(CLI::App& app) {
    app.add_option("--preset", flags.preset, "preset: paper-1 ... paper-5")->required();
    add_integer_option(app, "--seed", flags.seed, "seed (default 0: the preset's own)");
    app.add_option("--out", flags.out, "output hmsm-tree JSON file")->required();
}

int run_generate(CLI::App&) {
    auto tree = generate_preset(flags.preset, flags.seed);
    if (!tree) return fail(tree.status());
    Status saved = save_tree(*tree, flags.out);
    if (!saved) return fail(saved);
    return kExitOk;
}

}  // namespace hmsm::cli
