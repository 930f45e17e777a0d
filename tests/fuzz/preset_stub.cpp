// The fuzz build links only the parsers. "preset:NAME" in a forest calls generate_preset, which
// takes up to a second per preset: far too slow per fuzz input, and not parser code. This stub
// keeps the contract the parser relies on (known names give a valid tree, others an
// invalid_argument error naming the preset) with a tiny tree. The real generator is fuzzed
// through the catalog and generator tests, not here.
#include <hmsm/generator.h>

namespace hmsm {

const std::vector<std::string_view>& preset_names() {
    static const std::vector<std::string_view> names = {"paper-1", "paper-2", "paper-3", "paper-4", "paper-5"};
    return names;
}

Result<TreeModel> generate_preset(std::string_view name, uint64_t) {
    for (std::string_view known : preset_names())
        if (known == name) {
            TreeModel tree;
            tree.nodes.push_back({-1, {0, 0, 0}, 0.3});
            tree.nodes.push_back({0, {0, 5, 0}, 0.2});
            return tree;
        }
    return Status{ErrorCode::invalid_argument, "unknown preset '" + std::string(name) + "'"};
}

}  // namespace hmsm
