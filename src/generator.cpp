// Placeholder until the preset generator lands (work in progress in this session).
#include <hmsm/generator.h>

namespace hmsm {

const std::vector<std::string_view>& preset_names() {
    static const std::vector<std::string_view> names = {"paper-1", "paper-2", "paper-3", "paper-4", "paper-5"};
    return names;
}

Result<TreeModel> generate_preset(std::string_view name, uint64_t) {
    return Status{ErrorCode::invalid_argument, "preset '" + std::string(name) + "' is not implemented yet"};
}

}  // namespace hmsm
