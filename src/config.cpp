// The names of the configuration vocabulary (include/hmsm/config.h, include/hmsm/pass.h), each
// read from its one table.
#include <hmsm/config.h>
#include <hmsm/pass.h>

namespace hmsm {

const char* to_string(BackendKind kind) { return name_in(kBackendKindNames, kind); }
std::optional<BackendKind> parse_backend_kind(std::string_view name) {
    return value_named(kBackendKindNames, name);
}

const char* to_string(Composition composition) { return name_in(kCompositionNames, composition); }
std::optional<Composition> parse_composition(std::string_view name) {
    return value_named(kCompositionNames, name);
}

const char* to_string(VertexLayout layout) { return name_in(kVertexLayoutNames, layout); }
std::optional<VertexLayout> parse_vertex_layout(std::string_view name) {
    return value_named(kVertexLayoutNames, name);
}

const char* to_string(InstanceLayout layout) { return name_in(kInstanceLayoutNames, layout); }
std::optional<InstanceLayout> parse_instance_layout(std::string_view name) {
    return value_named(kInstanceLayoutNames, name);
}

const char* to_string(Outputs outputs) { return name_in(kOutputsNames, outputs); }
std::optional<Outputs> parse_outputs(std::string_view name) {
    return value_named(kOutputsNames, name);
}

std::optional<Pass> parse_pass(std::string_view name) {
    for (Pass p : kAllPasses)
        if (pass_name(p) == name) return p;
    return std::nullopt;
}

uint32_t output_components(Output output) {
    switch (output) {
        case Output::joint_matrices: return 12;
        case Output::chain_rotations: return 9;
        case Output::chain_angles: return 4;
        default: return 3;
    }
}

}  // namespace hmsm
